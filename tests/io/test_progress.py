"""Progress bars on a terminal only (io/progress.py, issue 50): drawn on a
pseudo-terminal, never into a pipe; the quiet log prints nothing."""

from __future__ import annotations

from io_progress_helpers import run_on_terminal

SCRIPT = ("from cfa_mitsuba.io.progress import progress_bar, stderr_log\n"
          "bar = progress_bar(3, 'work', enabled={enabled})\n"
          "for _ in range(3): bar.update(1)\n"
          "bar.close(); stderr_log({quiet})('a log line')\n")


def test_a_bar_on_a_terminal_and_none_in_a_pipe():
    on_tty = run_on_terminal(SCRIPT.format(enabled=True, quiet=False), tty=True)
    assert "work:" in on_tty and "/3 [" in on_tty and "a log line" in on_tty
    piped = run_on_terminal(SCRIPT.format(enabled=True, quiet=False), tty=False)
    assert "work:" not in piped and "a log line" in piped


def test_quiet_draws_and_logs_nothing():
    assert run_on_terminal(SCRIPT.format(enabled=False, quiet=True), tty=True).strip() == ""
