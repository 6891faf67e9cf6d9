"""Native sessions in a child process.

A fault inside the native code or a library under it (a segfault, MUMPS calling abort) ends the
child, not Blender: the call that was waiting on it raises QGPError naming the signal and the
child's last output. WorkerSession has binding.Session's interface; requests and answers are
pickled over a socket pair (on Windows, which cannot hand a socket to a child process, over a
loopback connection the child makes back, proven by a one-time token). Run as a script, this file
is the child: it serves one session. The
child's interpreter runs isolated from the user's Python setup (-I, no PYTHON* variables) and writes
no bytecode (-B), so nothing lands in the add-on's folder.
"""
import os
import pickle
import secrets
import signal
import socket
import struct
import subprocess
import sys
import tempfile

if __package__:
    from . import binding
else:  # the child, run as a script in isolated mode: its sys.path lacks the script's folder, so
    # this file's folder (the add-on's core package, bpy-free) is put first explicitly.
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import binding

ERR_WORKER_DIED = binding.ERR_INTERNAL


class _Channel:
    """Pickled messages over a stream socket, each prefixed by its length. (Not
    multiprocessing.connection: importing multiprocessing makes Debian's Blender 3.4 crash at exit.)"""

    def __init__(self, sock):
        self._sock = sock

    def send(self, message):
        data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
        self._sock.sendall(struct.pack("<Q", len(data)) + data)

    def recv(self):
        size = struct.unpack("<Q", self._read(8))[0]
        return pickle.loads(self._read(size))

    def _read(self, size):
        chunks, left = [], size
        while left:
            chunk = self._sock.recv(min(left, 1 << 24))
            if not chunk:
                raise EOFError("the other side closed the channel")
            chunks.append(chunk)
            left -= len(chunk)
        return b"".join(chunks)

    def close(self):
        self._sock.close()


class WorkerStartError(binding.QGPError):
    """The child process could not be started (no usable Python or numpy): nothing native ran."""


def child_environment():
    """The child's environment: the user's, without any PYTHON* variable (PYTHONPATH, PYTHONHOME,
    PYTHONSTARTUP, ... could make the interpreter import other modules or fail to start; the
    interpreter's -I ignores them as well), and QGP_LIBRARY naming the library this process loaded."""
    env = {name: value for name, value in os.environ.items() if not name.startswith("PYTHON")}
    if binding.loaded_library_path():
        env["QGP_LIBRARY"] = binding.loaded_library_path()
    return env


def child_command(*channel):
    """The child's command line: isolated mode (-I: no PYTHON* variables, no user site-packages, no
    script folder on sys.path) and no bytecode written (-B: no __pycache__ in the add-on's folder),
    then how it reaches the parent: an inherited socket's fd, or "--connect PORT TOKEN"."""
    return [python_executable(), "-I", "-B", os.path.abspath(__file__)] + [str(part) for part in channel]


def python_executable():
    """The interpreter Blender embeds (same version and packages), not whatever `python` is on PATH."""
    names = ("python.exe",) if os.name == "nt" else (f"python{sys.version_info.major}.{sys.version_info.minor}",)
    for prefix in (sys.prefix, sys.base_prefix):
        for name in names:
            candidate = os.path.join(prefix, "bin", name)
            if os.access(candidate, os.X_OK):
                return candidate
    return sys.executable


# Seconds the parent waits for the child to connect back (a loopback channel): the child's
# interpreter start and the library load come first.
CONNECT_TIMEOUT = 60


def start_child(log, loopback):
    """Starts the child process; returns it and the parent's end of the channel. loopback: the child
    connects to a listening socket on 127.0.0.1 and sends a one-time token first (Windows: no socket
    passing); otherwise the child inherits one end of a socket pair."""
    options = dict(stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT, env=child_environment())
    if not loopback:
        parent, child = socket.socketpair()
        try:
            process = subprocess.Popen(child_command(child.fileno()), pass_fds=(child.fileno(),), close_fds=True,
                                       **options)
        except OSError:
            parent.close()
            raise
        finally:
            child.close()
        return process, parent
    token = secrets.token_hex(16)
    with socket.create_server(("127.0.0.1", 0)) as listener:
        listener.settimeout(CONNECT_TIMEOUT)
        process = subprocess.Popen(child_command("--connect", listener.getsockname()[1], token), **options)
        try:
            parent, _ = listener.accept()
            parent.settimeout(None)
            if _Channel(parent)._read(len(token)).decode(errors="replace") != token:
                parent.close()
                raise OSError("a process other than the worker connected to it")
        except (OSError, EOFError) as e:
            process.kill()
            process.wait()
            raise OSError(f"the worker did not connect back ({e})")
    return process, parent


class WorkerSession(binding.SessionLifetime):
    """A binding.Session living in its own process. Use as a context manager or call close()."""

    def __init__(self, vertices, triangles, loopback=os.name == "nt"):
        self._process = None
        self._conn = None
        self._log = tempfile.TemporaryFile()
        try:
            self._process, parent = start_child(self._log, loopback)
        except OSError as e:
            raise WorkerStartError(binding.ERR_INTERNAL, f"cannot start the worker process: {e}")
        self._conn = _Channel(parent)
        try:
            self._call("version")
        except binding.QGPError as e:
            self.close()
            raise WorkerStartError(e.code, e.message)
        self._call("create", vertices, triangles)

    @property
    def pid(self):
        return self._process.pid if self._process else None

    @property
    def alive(self):
        return self._process is not None and self._process.poll() is None

    def _reap(self):
        """Waits up to 10 s for the child to end, then kills it; its exit status."""
        try:
            return self._process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self._process.kill()
            return self._process.wait()

    def _died(self):
        code = self._reap()
        if code < 0:
            try:
                how = f"was killed by {signal.Signals(-code).name}"
            except ValueError:
                how = f"was killed by signal {-code}"
        else:
            how = f"exited with status {code}"
        self._log.seek(0)
        lines = [s.strip() for s in self._log.read().decode(errors="replace").splitlines() if s.strip()]
        last = f"; its last output: {' | '.join(lines[-3:])}" if lines else ""
        self._conn.close()
        self._conn = None
        return binding.QGPError(ERR_WORKER_DIED, f"the native job's process {how}{last}. "
                                                 "Blender and the scene are unaffected")

    def _call(self, method, *args):
        if self._conn is None:
            raise binding.QGPError(ERR_WORKER_DIED, "the native job's process has ended")
        try:
            self._conn.send((method, args))
            status, value = self._conn.recv()
        except (EOFError, OSError):
            raise self._died() from None
        if status == "error":
            raise binding.QGPError(*value)
        return value

    # -- lifetime --
    def close(self):
        if self._conn is not None:
            try:
                self._conn.send(("close", ()))
                self._conn.recv()
            except (EOFError, OSError):
                pass
            self._conn.close()
            self._conn = None
        if self._process is not None:
            self._reap()
            self._process = None
        if self._log is not None:
            self._log.close()
            self._log = None

    # -- binding.Session's interface, forwarded --
    def set_option(self, name, value):
        self._call("set_option", name, value)

    def set_option_string(self, name, value):
        self._call("set_option_string", name, value)

    def set_features(self, edges):
        self._call("set_features", edges)

    def set_density(self, density):
        self._call("set_density", density)

    def start(self, job):
        self._call("start", job)

    def poll(self):
        return self._call("poll")

    def cancel(self):
        self._call("cancel")

    def wait(self, timeout=-1.0):
        return self._call("wait", timeout)

    def report(self):
        return self._call("report")

    def intake_mesh(self):
        return self._call("intake_mesh")

    def quad_mesh(self):
        return self._call("quad_mesh")

    def kept_triangles(self):
        return self._call("kept_triangles")

    def grid_uv(self, num_triangles):
        return self._call("grid_uv", num_triangles)

    def uv_mesh(self):
        return self._call("uv_mesh")

    def layout_lines(self):
        return self._call("layout_lines")


def connect_to_parent(argv):
    """The child's end of the channel, from its command line (see child_command)."""
    if argv[0] == "--connect":
        sock = socket.create_connection(("127.0.0.1", int(argv[1])))
        sock.sendall(argv[2].encode())
        return sock
    return socket.socket(fileno=int(argv[0]))


def serve(sock):
    """The child's loop: one session, requests until "close" or the parent goes away."""
    conn = _Channel(sock)
    session = None
    try:
        while True:
            try:
                method, args = conn.recv()
            except (EOFError, OSError):
                break
            if method == "close":
                conn.send(("ok", None))
                break
            try:
                if method == "version":
                    value = binding.version()
                elif method == "create":
                    session = binding.Session(*args)
                    value = None
                else:
                    value = getattr(session, method)(*args)
                conn.send(("ok", value))
            except binding.QGPError as e:
                conn.send(("error", (e.code, e.message)))
            except Exception as e:  # a bug on this side: reported, the child stays usable
                conn.send(("error", (binding.ERR_INTERNAL, f"worker: {type(e).__name__}: {e}")))
    finally:
        if session is not None:
            session.close()


if __name__ == "__main__":
    try:
        import resource
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))  # a crash leaves no core file in the user's folder
    except (ImportError, ValueError, OSError):
        pass
    serve(connect_to_parent(sys.argv[1:]))
