"""Run by test_modal.py in a windowed Blender (under xvfb-run, with --enable-event-simulate):

    blender --factory-startup --enable-event-simulate --python THIS -- --result FILE

Runs Quantized Retopo through its modal path (invoke: timer, progress bar, status text) as a user
would from the menu, twice: once to the end (a torus), once pressed Esc on while the native job runs
(a dense sphere). Window.event_simulate presses Esc; real input is ignored. Every call of the
operator's modal() is recorded (event, return value). The facts go to FILE as JSON for the parent
to check; Blender then exits. (Not named test_*.py: ctest would run it with blender -b.)"""
import json
import os
import sys
import time
import traceback

import bpy

ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
RESULT = ARGS[ARGS.index("--result") + 1]
MODULE = "quantized_retopo"
DEADLINE = time.time() + float(os.environ.get("QGP_GUI_TIMEOUT", "600"))

result = {"runs": {}}
calls = []  # (event type, sorted return value) of every modal() call


def finish(**facts):
    result.update(facts)
    with open(RESULT, "w") as f:
        json.dump(result, f, indent=2)
    operators = sys.modules.get(MODULE + ".operators")
    if operators is not None:
        for entry in operators._session_cache.values():  # (settings, session, fallback)
            entry[1].close()
    sys.stdout.flush()
    os._exit(0)


def scene_state():
    state = []
    for obj in sorted(bpy.data.objects, key=lambda o: o.name):
        entry = [obj.name, obj.select_get(), obj.hide_get()]
        if obj.type == "MESH":
            m = obj.data
            entry += [len(m.vertices), len(m.polygons), [layer.name for layer in m.uv_layers],
                      hash(tuple(v.co[:] for v in m.vertices))]
        state.append(entry)
    return [state, len(bpy.data.meshes)]


def window_override():
    window = bpy.context.window_manager.windows[0]
    return bpy.context.temp_override(window=window, screen=window.screen, workspace=window.workspace)


def new_source(add, **options):
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    add(**options)
    return bpy.context.active_object


def invoke(source, target_faces):
    for other in bpy.context.selected_objects:
        other.select_set(False)
    source.select_set(True)
    bpy.context.view_layer.objects.active = source
    with window_override():
        return sorted(bpy.ops.object.qgp_quad_remesh("INVOKE_DEFAULT", target_faces=target_faces))


class Steps:
    """The script's state machine, advanced by an app timer (the modal operator runs meanwhile)."""

    def __init__(self):
        self.step = self.start_control
        self.source = None
        self.before = None
        self.calls_at_start = 0
        self.ticks = []  # when this timer ran: Blender's main loop kept going

    def __call__(self):
        self.ticks.append(time.time())
        try:
            if time.time() > DEADLINE:
                finish(error=f"timed out in {self.step.__name__}", calls=calls[-20:])
            self.step()
        except Exception:
            finish(error=traceback.format_exc(), calls=calls[-20:])
        return 0.1

    def ended(self):
        """The return value of the modal() call that ended the current run, if any."""
        for event, value in calls[self.calls_at_start:]:
            if value not in (["RUNNING_MODAL"], ["PASS_THROUGH"]):
                return event, value
        return None

    # 1. a modal run to its end: the control (the harness sees a finished run as finished)
    def start_control(self):
        self.source = new_source(bpy.ops.mesh.primitive_torus_add, major_segments=48, minor_segments=16)
        self.calls_at_start = len(calls)
        result["runs"]["control"] = {"invoke": invoke(self.source, 300), "started": time.time()}
        self.step = self.wait_control

    def wait_control(self):
        end = self.ended()
        if end is None:
            return
        run = result["runs"]["control"]
        run.update(ended_by=end, seconds=time.time() - run["started"],
                   events=[c for c in calls[self.calls_at_start:] if c[0] != "TIMER"],
                   running_timer_calls=sum(c == ("TIMER", ["RUNNING_MODAL"]) for c in calls[self.calls_at_start:]),
                   quads=len(bpy.data.objects[self.source.name + "_quads"].data.polygons)
                   if self.source.name + "_quads" in bpy.data.objects else None,
                   source_hidden=self.source.hide_get())
        self.step = self.start_esc

    # 2. a long modal run, Esc pressed while the native job runs
    def start_esc(self):
        self.source = new_source(bpy.ops.mesh.primitive_uv_sphere_add, segments=800, ring_count=400)
        self.before = scene_state()
        self.calls_at_start = len(calls)
        result["runs"]["esc"] = {"invoke": invoke(self.source, 800), "started": time.time()}
        self.step = self.press_esc

    def press_esc(self):
        run = result["runs"]["esc"]
        operators = sys.modules[MODULE + ".operators"]
        binding = sys.modules[MODULE + ".core.binding"]
        progress = sum(c == ("TIMER", ["RUNNING_MODAL"]) for c in calls[self.calls_at_start:])
        if self.ended() is not None:
            run["ended_before_esc"] = self.ended()
            self.step = self.check_esc
            return
        if progress < 3:  # wait until the modal timer has reported progress a few times
            return
        session = operators._session_cache[self.source.name][1]
        run["state_at_esc"], _, run["stage_at_esc"] = session.poll()
        run["running"] = binding.STATE_RUNNING
        run["running_timer_calls"] = progress
        run["esc_at"] = self.ticks[-1]  # this tick: the stall measure starts here
        bpy.context.window_manager.windows[0].event_simulate(type="ESC", value="PRESS")
        self.step = self.check_esc

    def check_esc(self):
        end = self.ended()
        if end is None:
            return
        run = result["runs"]["esc"]
        operators = sys.modules[MODULE + ".operators"]
        binding = sys.modules[MODULE + ".core.binding"]
        since_esc = [t for t in self.ticks if t >= run.get("esc_at", time.time())]
        run.update(ended_by=end, seconds_after_esc=time.time() - run.get("esc_at", time.time()),
                   esc_calls=[c for c in calls[self.calls_at_start:] if c[0] == "ESC"],
                   longest_stall_after_esc=max((b - a for a, b in zip(since_esc, since_esc[1:])), default=0.0),
                   scene_unchanged=scene_state() == self.before,
                   objects=sorted(o.name for o in bpy.data.objects),
                   state_after=operators._session_cache[self.source.name][1].poll()[0],
                   cancelled=binding.STATE_CANCELLED)
        finish(ok=True)


def main():
    bpy.ops.preferences.addon_enable(module=MODULE)
    operators = sys.modules[MODULE + ".operators"]
    modal = operators.OBJECT_OT_qgp_quad_remesh.modal

    def recording_modal(self, context, event):
        event_type = event.type  # read first: a timer event reads as NONE once its timer is removed
        value = modal(self, context, event)
        calls.append((event_type, sorted(value)))
        return value

    operators.OBJECT_OT_qgp_quad_remesh.modal = recording_modal
    result["window"] = bpy.context.window is not None
    bpy.app.timers.register(Steps(), first_interval=0.5)


try:
    main()
except Exception:
    finish(error=traceback.format_exc())
