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


def wait_for_cpu_seconds(proc, seconds, wall_limit=120.0):
    """Waits until the process has used `seconds` of CPU time (inside the pipeline whatever the machine's
    load); returns whether it is still running."""
    start = time.monotonic()
    tick = os.sysconf("SC_CLK_TCK")
    while proc.poll() is None and time.monotonic() - start < wall_limit:
        try:
            with open(f"/proc/{proc.pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            if (int(fields[11]) + int(fields[12])) / tick >= seconds:  # utime + stime
                break
        except (OSError, IndexError, ValueError):
            pass
        time.sleep(0.02)
    return proc.poll() is None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--qgp", required=True)
    ap.add_argument("--meshes", required=True)
    ap.add_argument("--exit-preload", required=True, help="shared library calling exit(0) after a delay")
    args = ap.parse_args()
    failures = []
    # A long run (about 30 s), ended after 5 s of its CPU time: in quantization, whatever the machine's
    # load. Not inside a METIS call (CHOLMOD's nested dissection in the seamless map's repair): METIS
    # (GKlib) traps SIGABRT while it runs and turns it into an error return, so a SIGABRT sent then is
    # swallowed and the run completes (mnf07 with sharp edges, signalled after 1.5 s of wall time,
    # sometimes landed there).
    run = [os.path.join(args.meshes, "dragon-genus1.obj"), "--faces", "2000"]
    cpu_seconds = 5.0
    with tempfile.TemporaryDirectory() as tmp:
        for sig, words in ((signal.SIGSEGV, "crashed (SIGSEGV)"), (signal.SIGABRT, "aborted (SIGABRT)")):
            out = os.path.join(tmp, f"out_{sig.name}.obj")
            proc = subprocess.Popen([args.qgp, "remesh", *run, "-o", out], stdout=subprocess.PIPE,
                                    stderr=subprocess.PIPE, text=True)
            running = wait_for_cpu_seconds(proc, cpu_seconds)
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
        env = dict(os.environ, LD_PRELOAD=os.path.abspath(args.exit_preload),
                   QGP_TEST_EXIT_AFTER_MS=str(int(1000 * cpu_seconds)))
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
