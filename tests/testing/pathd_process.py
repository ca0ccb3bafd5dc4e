"""The pathd process launcher of the Python tests, the counterpart of
tests/testing/pathd_process.h: starts pathd on a free loopback port, reads
its listening line for the address, sends its log (stderr) to a file or to
the caller's stderr, and stops it with SIGTERM and a bounded wait that falls
back to SIGKILL. The kernel kills the daemon if the test dies.

Scripts import it after putting this folder on sys.path:
    sys.path.insert(0, str(SOURCE_DIR / "tests" / "testing"))
"""

import ctypes
import os
import select
import signal
import subprocess
import time

# The line pathd prints on stdout once it serves: this prefix, then
# HOST:PORT (server/listening_line.h defines it for C++).
LISTENING_PREFIX = "pathd listening on "
# With --http_address, the second line: this prefix, then the HTTP HOST:PORT.
HTTP_PREFIX = "pathd http on "

# Hang guard of every wait: generous for a loaded machine, never a timing
# assertion.
BOUND_SECONDS = 120.0


def _die_with_parent() -> None:
    # Runs in the child before exec: the kernel kills pathd if the test dies.
    pr_set_pdeathsig = 1
    ctypes.CDLL("libc.so.6", use_errno=True).prctl(pr_set_pdeathsig, signal.SIGKILL)


class ExitedBeforeListening(RuntimeError):
    """pathd exited before its listening line; `code` is its exit code."""

    def __init__(self, message, code):
        super().__init__(message)
        self.code = code


class PathdProcess:
    """One pathd: `flags` after --address=127.0.0.1:0, `extra_env` added to
    the environment; its log appended to `log_path` (None: the caller's
    stderr). Raises RuntimeError, naming the exit code or the first line,
    when no listening line comes (ExitedBeforeListening when it exited)."""

    def __init__(self, binary, flags=(), log_path=None, bound=BOUND_SECONDS,
                 extra_env=None):
        self.bound = bound
        self.log_path = log_path
        self._pending = b""
        self._log = open(log_path, "ab") if log_path is not None else None
        env = {k: v for k, v in os.environ.items() if k != "PATHD_SERVER"}
        env.update(extra_env or {})
        self.proc = subprocess.Popen(
            [binary, "--address=127.0.0.1:0", *flags],
            stdout=subprocess.PIPE, stderr=self._log, env=env,
            preexec_fn=_die_with_parent)
        try:
            line = self._read_line()
        except RuntimeError:
            self.kill()
            raise
        if not line.startswith(LISTENING_PREFIX):
            self.kill()
            raise RuntimeError(f"{binary}: unexpected first stdout line '{line}'"
                               f"{self._see_log()}")
        self.address = line[len(LISTENING_PREFIX):]
        # The HTTP API's address when the flags ask for one, else None.
        self.http_address = None
        if any(f.startswith("--http_address=") and f != "--http_address=" for f in flags):
            line = self._read_line()
            if not line.startswith(HTTP_PREFIX):
                self.kill()
                raise RuntimeError(f"{binary}: expected '{HTTP_PREFIX}...', got '{line}'"
                                   f"{self._see_log()}")
            self.http_address = line[len(HTTP_PREFIX):]

    def _see_log(self):
        return f"; see {self.log_path}" if self.log_path is not None else ""

    def _read_line(self):
        """The next stdout line, without its newline."""
        fd = self.proc.stdout.fileno()
        deadline = time.monotonic() + self.bound
        data = self._pending
        while b"\n" not in data:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise RuntimeError(f"pathd printed no listening line within "
                                   f"{self.bound:.0f} s{self._see_log()}")
            ready, _, _ = select.select([fd], [], [], min(remaining, 1.0))
            if not ready:
                continue
            chunk = os.read(fd, 4096)
            if not chunk:
                code = self.proc.wait(timeout=self.bound)
                raise ExitedBeforeListening(
                    f"pathd exited (code {code}) before listening"
                    f"{self._see_log()}", code)
            data += chunk
        line, self._pending = data.split(b"\n", 1)
        return line.decode()

    def stop(self):
        """SIGTERM, then the exit code (negative: the signal that ended it);
        past the bound, SIGKILL and RuntimeError."""
        self.proc.send_signal(signal.SIGTERM)
        try:
            code = self.proc.wait(timeout=self.bound)
        except subprocess.TimeoutExpired:
            self.kill()
            raise RuntimeError(f"pathd ignored SIGTERM for {self.bound:.0f} s; "
                               f"killed it{self._see_log()}") from None
        self._close()
        return code

    def kill(self):
        """SIGKILL, and reap."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGKILL)
        self.proc.wait()
        self._close()

    def wait(self, timeout):
        """Waits up to `timeout` s for pathd to exit by itself: its exit code,
        or None while it still runs."""
        try:
            code = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            return None
        self._close()
        return code

    def _close(self):
        self.proc.stdout.close()
        if self._log is not None and not self._log.closed:
            self._log.close()
