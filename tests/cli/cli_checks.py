"""What the CLI test scripts share: running qgp, and checks that print and collect failures."""
import subprocess

FAILURES = []


def check(condition, what):
    print(("ok   " if condition else "FAIL ") + what)
    if not condition:
        FAILURES.append(what)


def run(qgp, *args, env=None):
    """qgp with the arguments (in `env`, the environment, when given)."""
    return subprocess.run([qgp, *map(str, args)], capture_output=True, text=True, env=env)


def summary():
    """Prints how many checks failed; the exit status (1 if any did)."""
    print(f"{len(FAILURES)} failure(s)")
    return 1 if FAILURES else 0
