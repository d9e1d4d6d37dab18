"""Stopping the farm processes a Python test started (the server last: workers first leave)."""
import subprocess


def stop_all(procs, timeout=10):
    """SIGTERM each of procs, newest first; waits up to timeout s each, then SIGKILL."""
    for p in reversed(procs):
        if p.poll() is None:
            p.terminate()
    for p in procs:
        try:
            p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
