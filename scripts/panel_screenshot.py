"""Screenshots of the add-on's sidebar panel and of Quantized Retopo's redo panel, for the README.
Runs in a windowed Blender (3.4 or later) on a virtual X display (Debian package xvfb):

    QGP_LIBRARY=build/lib/libqgp.so xvfb-run -a -s "-screen 0 1600x1000x24" \\
        blender --factory-startup --enable-event-simulate --python scripts/panel_screenshot.py -- \\
        --out docs/images/panel.png [--redo-out docs/images/redo_panel.png] [--library PATH]

Enables the add-on from this checkout (addon/, not installed), adds Suzanne, opens the 3D
viewport's sidebar at its default width and turns it to the Retopo tab (Ctrl+Wheel over the
sidebar, simulated: Blender 3.4 has no Python API for the active tab, hence
--enable-event-simulate), saves the sidebar as --out. With --redo-out it then runs Quantized Retopo
(500 quads) as from the menu, opens its redo panel ("Adjust Last Operation", collapsed at first)
with a simulated click and saves it. Region overlap and the splash are turned off (this session
only: --factory-startup saves no preferences) so that the sidebar has a plain background the crop
trims to the panels. The native library: --library, else $QGP_LIBRARY, else build/lib/libqgp.so of this
checkout. Blender exits with 0 when the pictures are written, 1 (and a message) otherwise."""
import os
import shutil
import sys
import tempfile
import time
import traceback

import bpy
import numpy

ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODULE = "quantized_retopo"
DEADLINE = time.time() + 300
TEMPORARY = []  # folders removed on exit (the add-on's link, the full screenshots)
MARGIN = 6  # pixels kept below the last panel
BORDER = 10  # the region's lowest rows (its border) are not the background the trim compares with


def argument(name, default=None):
    return ARGS[ARGS.index(name) + 1] if name in ARGS else default


def finish(error=None):
    if error:
        print("panel_screenshot: " + error, file=sys.stderr)
    operators = sys.modules.get(MODULE + ".operators")
    if operators is not None:
        for entry in operators._session_cache.values():  # (settings, session, fallback)
            entry[1].close()
    for folder in TEMPORARY:
        shutil.rmtree(folder, ignore_errors=True)  # the link to addon/ goes, not addon/
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(1 if error else 0)


def enable_addon():
    """Imports addon/ as the package `quantized_retopo` (a link in a temporary folder on sys.path)
    and enables it; the library comes from QGP_LIBRARY."""
    library = argument("--library") or os.environ.get("QGP_LIBRARY") or os.path.join(REPO, "build", "lib",
                                                                                     "libqgp.so")
    if not os.path.exists(library):
        finish(f"no native library at {library} (build it, or pass --library / set QGP_LIBRARY)")
    os.environ["QGP_LIBRARY"] = os.path.abspath(library)
    folder = tempfile.mkdtemp(prefix="qgp_shot_")
    TEMPORARY.append(folder)
    os.symlink(os.path.join(REPO, "addon"), os.path.join(folder, MODULE))
    sys.path.insert(0, folder)
    bpy.ops.preferences.addon_enable(module=MODULE)
    if MODULE not in bpy.context.preferences.addons:
        finish("the add-on could not be enabled")


def view3d():
    """(window, area, the sidebar region, the main region) of the first 3D viewport."""
    window = bpy.context.window_manager.windows[0]
    for area in window.screen.areas:
        if area.type == "VIEW_3D":
            regions = {region.type: region for region in area.regions}
            return window, area, regions["UI"], regions["WINDOW"]
    finish("no 3D viewport in the window")


def save_crop(window, rect, path, trim=False):
    """Saves the window's pixels inside rect (x, y, width, height in window coordinates, from the
    bottom left) as a PNG at path; with trim, the rows at the bottom that are plain background (as
    the row BORDER pixels above the region's bottom edge) are dropped: the sidebar below the panels."""
    TEMPORARY.append(tempfile.mkdtemp(prefix="qgp_shot_"))
    full = os.path.join(TEMPORARY[-1], "window.png")
    with bpy.context.temp_override(window=window, screen=window.screen):
        bpy.ops.screen.screenshot(filepath=full)
    shot = bpy.data.images.load(full)
    width, height = shot.size
    pixels = numpy.empty(width * height * 4, dtype=numpy.float32)
    shot.pixels.foreach_get(pixels)
    pixels = pixels.reshape(height, width, 4)
    x, y, w, h = rect
    crop = pixels[y:y + h, x:x + w].copy()
    if trim:
        # Row 0 is the lowest; a difference of more than 4 levels (of 255) is not background.
        differs = numpy.any(numpy.abs(crop[BORDER:] - crop[BORDER]) > 4 / 255, axis=(1, 2))
        if differs.any():
            crop = crop[max(BORDER + int(numpy.argmax(differs)) - MARGIN, 0):]
    crop[:, :, 3] = 1.0
    out = bpy.data.images.new("qgp_shot", crop.shape[1], crop.shape[0], alpha=False)
    out.pixels.foreach_set(crop.ravel())
    out.filepath_raw = os.path.abspath(path)
    out.file_format = "PNG"
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    out.save()
    print(f"panel_screenshot: {path}: {crop.shape[1]} x {crop.shape[0]} px")
    bpy.data.images.remove(shot)
    bpy.data.images.remove(out)


class Steps:
    """The script's state machine, advanced by an app timer so that Blender draws in between."""

    def __init__(self):
        self.step = self.open_sidebar
        self.retopo_drawn = False  # the Retopo panel drew since this was last reset
        self.wait = 0
        self.tries = 0

    def __call__(self):
        try:
            if time.time() > DEADLINE:
                finish(f"timed out in {self.step.__name__}")
            if self.wait > 0:
                self.wait -= 1
            else:
                self.step()
        except Exception:
            finish(traceback.format_exc())
        return 0.2

    def open_sidebar(self):
        window, area, _, main = view3d()
        with bpy.context.temp_override(window=window, area=area, region=main):
            for obj in list(bpy.data.objects):
                bpy.data.objects.remove(obj)
            bpy.ops.mesh.primitive_monkey_add()
            bpy.context.active_object.modifiers.new("Subdivision", "SUBSURF").levels = 1
        area.spaces.active.show_region_ui = True
        self.step, self.wait = self.next_tab, 3

    def next_tab(self):
        """Ctrl+Wheel over the sidebar shows its next tab, until the Retopo panel draws."""
        window, area, sidebar, _ = view3d()
        if self.tries > 12:
            finish("the sidebar never showed the Retopo tab")
        self.tries += 1
        x, y = sidebar.x + sidebar.width // 2, sidebar.y + sidebar.height // 2
        window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
        window.event_simulate(type="WHEELDOWNMOUSE", value="PRESS", x=x, y=y, ctrl=True)
        self.step, self.wait = self.redraw, 2

    def redraw(self):
        self.retopo_drawn = False
        view3d()[1].tag_redraw()
        self.step, self.wait = self.check_tab, 2

    def check_tab(self):
        self.step = self.shoot_sidebar if self.retopo_drawn else self.next_tab

    def shoot_sidebar(self):
        window, _, sidebar, _ = view3d()
        save_crop(window, (sidebar.x, sidebar.y, sidebar.width, sidebar.height), argument("--out"), trim=True)
        self.step = self.run_operator if argument("--redo-out") else self.done

    def run_operator(self):
        window, area, _, main = view3d()
        with bpy.context.temp_override(window=window, area=area, region=main):
            # undo=True: registered as from the menu, so the redo panel shows.
            result = bpy.ops.object.qgp_quad_remesh("EXEC_DEFAULT", True, target_faces=500)
        if result != {"FINISHED"}:
            finish(f"Quantized Retopo returned {result}")
        self.step, self.wait = self.open_redo, 5

    def redo_region(self):
        window, area, _, _ = view3d()
        hud = [region for region in area.regions if region.type == "HUD"]
        if not hud or hud[0].width <= 1:
            finish("no redo panel after Quantized Retopo")
        return window, hud[0]

    def open_redo(self):
        """The redo panel starts collapsed (its header only): a click on the header opens it."""
        window, hud = self.redo_region()
        self.collapsed_height = hud.height
        x, y = hud.x + hud.width // 2, hud.y + hud.height - hud.height // 2
        window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
        window.event_simulate(type="LEFTMOUSE", value="PRESS", x=x, y=y)
        window.event_simulate(type="LEFTMOUSE", value="RELEASE", x=x, y=y)
        self.step, self.wait = self.shoot_redo, 5

    def shoot_redo(self):
        window, hud = self.redo_region()
        if hud.height <= self.collapsed_height:
            finish("the redo panel did not open")
        save_crop(window, (hud.x, hud.y, hud.width, hud.height), argument("--redo-out"))
        self.step = self.done

    def done(self):
        finish()


def main():
    if not argument("--out"):
        finish("usage: blender --factory-startup --enable-event-simulate --python panel_screenshot.py -- "
               "--out PANEL.png [--redo-out REDO.png] [--library libqgp.so]")
    if bpy.app.background:
        finish("needs a window: run under xvfb-run without -b")
    bpy.context.preferences.system.use_region_overlap = False
    bpy.context.preferences.view.show_splash = False
    enable_addon()
    steps = Steps()
    panel = sys.modules[MODULE + ".ui"].VIEW3D_PT_qgp_retopo
    draw = panel.draw

    def recording_draw(self, context):
        steps.retopo_drawn = True
        draw(self, context)

    panel.draw = recording_draw
    bpy.app.timers.register(steps, first_interval=0.5)


try:
    main()
except Exception:
    finish(traceback.format_exc())
