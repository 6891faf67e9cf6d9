"""The operators' modal path (blender -b --factory-startup --python-exit-code 1 --python THIS --):
what a user gets from the menu or the panel, a job on a timer with a progress bar that Esc cancels.

blender -b has no window, so no timer, modal handler or key press: this script installs the add-on
(as test_addon.py does) and runs gui_modal.py in a windowed Blender on a virtual X display
(xvfb-run, Debian package xvfb) started with --enable-event-simulate, where Window.event_simulate
presses Esc as a user would (real input is ignored). It checks what that run found: a modal run
finishes on its timer with the quads; Esc while the native job runs cancels the job without
blocking Blender, leaves the scene unchanged, and the operator returns CANCELLED."""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import addon_checks  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MODULE = "quantized_retopo"


def run_windowed():
    xvfb_run = shutil.which("xvfb-run")
    assert xvfb_run, "xvfb-run is missing: install the Debian package xvfb (scripts/setup.sh)"
    out = tempfile.mkdtemp(prefix="qgp_modal_")
    path = os.path.join(out, "result.json")
    command = [xvfb_run, "-a", "-s", "-screen 0 1280x1024x24", bpy.app.binary_path, "--factory-startup",
               "--enable-event-simulate", "--python", os.path.join(REPO, "tests", "blender", "gui_modal.py"),
               "--", "--result", path]
    proc = subprocess.run(command, capture_output=True, text=True, timeout=1200)
    log = (proc.stdout + proc.stderr)[-3000:]
    assert os.path.exists(path), f"the windowed Blender wrote no result (exit {proc.returncode}): {log}"
    with open(path) as f:
        result = json.load(f)
    assert "error" not in result, result["error"] + "\n" + log
    return result


def check(result):
    assert result["window"], "the windowed Blender had no window"
    control = result["runs"]["control"]
    assert control["invoke"] == ["RUNNING_MODAL"], control
    assert control["ended_by"] == ["TIMER", ["FINISHED"]], control
    assert control["quads"] and control["source_hidden"], control
    print(f"modal run: finished on the timer with {control['quads']} quads in {control['seconds']:.1f} s")
    esc = result["runs"]["esc"]
    assert esc["invoke"] == ["RUNNING_MODAL"], esc
    assert "ended_before_esc" not in esc, f"the job ended before Esc could be pressed: {esc}"
    assert esc["running_timer_calls"] >= 3, esc  # the timer reported the running job's progress
    assert esc["state_at_esc"] == esc["running"], esc  # Esc came while the native job ran
    # Esc asks the job to stop and the timer waits for it (Blender keeps running meanwhile: the
    # script's own 0.1 s timer never stalls for long), then the operator returns CANCELLED.
    assert esc["esc_calls"] == [["ESC", ["RUNNING_MODAL"]]], esc
    assert esc["ended_by"] == ["TIMER", ["CANCELLED"]], esc
    assert esc["longest_stall_after_esc"] < 10.0, esc
    assert esc["state_after"] == esc["cancelled"], esc  # the native job was cancelled, not left running
    assert esc["scene_unchanged"], esc
    print(f"Esc during {esc['stage_at_esc']}: the job stopped {esc['seconds_after_esc']:.1f} s later (Blender "
          f"stalled at most {esc['longest_stall_after_esc']:.2f} s meanwhile), the operator returned CANCELLED, "
          f"scene unchanged ({', '.join(esc['objects'])})")


def main():
    addon_checks.install_legacy_addon(REPO, MODULE, enable=False)
    check(run_windowed())
    print("modal test: OK")


main()
sys.stdout.flush()
