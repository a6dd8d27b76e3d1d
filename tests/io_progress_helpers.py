"""Run Python code with stderr on a pseudo-terminal (for the progress-bar
tests: a bar is drawn on a terminal only)."""

from __future__ import annotations

import fcntl
import os
import pty
import struct
import subprocess
import sys
import termios

from conftest import REPO


def run_on_terminal(code: str, *, tty: bool) -> str:
    """stderr of ``python -c code``, on a 120-column pseudo-terminal or a pipe."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    if not tty:
        return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                              timeout=120).stderr
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    proc = subprocess.Popen([sys.executable, "-c", code], stderr=slave, stdout=subprocess.DEVNULL, env=env)
    os.close(slave)
    out = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:
            break
        if not chunk:
            break
        out += chunk
    proc.wait(timeout=120)
    os.close(master)
    return out.decode(errors="replace")
