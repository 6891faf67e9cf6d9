#!/usr/bin/python3
"""`qgp remesh` ended mid-run by a fatal signal (as a crash inside a library would end it) or by a
library calling exit(0) (as MUMPS does on an internal error): stderr names what happened, the exit
status is the signal's or 4 (never 0), and no output file is written.
Usage: test_cli_abnormal_end.py --qgp QGP --meshes DIR --exit-preload SHIM.so"""
import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--qgp", required=True)
    ap.add_argument("--meshes", required=True)
    ap.add_argument("--exit-preload", required=True, help="shared library calling exit(0) after a delay")
    args = ap.parse_args()
    failures = []
    # A long run (about 20 s on 2 cores), so that the signal lands inside the pipeline.
    run = [os.path.join(args.meshes, "mnf07HeadFem_rem_rem_p.obj"), "--faces", "2000", "--sharp-angle", "60"]
    with tempfile.TemporaryDirectory() as tmp:
        for sig, words in ((signal.SIGSEGV, "crashed (SIGSEGV)"), (signal.SIGABRT, "aborted (SIGABRT)")):
            out = os.path.join(tmp, f"out_{sig.name}.obj")
            proc = subprocess.Popen([args.qgp, "remesh", *run, "-o", out], stdout=subprocess.PIPE,
                                    stderr=subprocess.PIPE, text=True)
            time.sleep(1.5)
            running = proc.poll() is None
            proc.send_signal(sig)
            _, err = proc.communicate(timeout=60)
            print(f"{sig.name}: exit {proc.returncode}, stderr: {err.strip()[-100:]}")
            if not running:
                failures.append(f"{sig.name}: the run ended before the signal")
            if proc.returncode != -sig:
                failures.append(f"{sig.name}: exit status {proc.returncode}, expected {-sig}")
            if words not in err or "no output was written" not in err:
                failures.append(f"{sig.name}: stderr does not say what happened: {err.strip()[-200:]}")
            if os.path.exists(out):
                failures.append(f"{sig.name}: {out} was written")
        out = os.path.join(tmp, "out_exit.obj")
        env = dict(os.environ, LD_PRELOAD=os.path.abspath(args.exit_preload), QGP_TEST_EXIT_AFTER_MS="1500")
        proc = subprocess.run([args.qgp, "remesh", *run, "-o", out], capture_output=True, text=True, env=env,
                              timeout=120)
        print(f"exit(0) from a library: exit {proc.returncode}, stderr: {proc.stderr.strip()[-100:]}")
        if proc.returncode != 4:
            failures.append(f"exit(0) from a library: exit status {proc.returncode}, expected 4")
        if "a library under the pipeline ended the process" not in proc.stderr:
            failures.append(f"exit(0) from a library: stderr does not say so: {proc.stderr.strip()[-200:]}")
        if os.path.exists(out):
            failures.append(f"exit(0) from a library: {out} was written")
    for f in failures:
        print("FAIL", f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
