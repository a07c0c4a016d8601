"""Files in and out, safely: meshio reads that fail with a named :class:`~pliant.errors.MeshError`
(meshio itself prints and calls ``sys.exit`` on some unreadable files), output paths checked before
any long computation, and writes that are atomic (a temporary name renamed into place) and that
report an unwritable path as an :class:`~pliant.errors.InputError` naming it."""

from __future__ import annotations

import contextlib
import io
import os
import signal
import stat
import tempfile
import threading
from pathlib import Path

from ..errors import InputError, MeshError
from ..memory import data_segment


# file_problem's answers that callers tell apart (the others are only shown).
MISSING = "no such file"
NOT_REGULAR = "not a regular file (a pipe, device or socket: reading it may never end)"


def file_problem(path) -> str | None:
    """Why ``path`` cannot be read as an input file (MISSING, "a folder, not a file", NOT_REGULAR,
    "cannot be read (...)"), or None when it can. A pipe, device or socket is refused: reading one
    may wait for ever for a writer (a named pipe) or never end (/dev/zero)."""
    try:
        mode = Path(path).stat().st_mode
    except FileNotFoundError:
        return MISSING
    except OSError as e:  # a link loop, a name too long, no permission on a folder above it
        return f"cannot be read ({e.strerror or e})"
    if stat.S_ISDIR(mode):
        return "a folder, not a file"
    if not stat.S_ISREG(mode):
        return NOT_REGULAR
    return None


class _EndOfFileRaises(io.BufferedReader):
    """A file that raises meshio's ReadError when read again at its end. Some of meshio's readers
    loop for ever once a cut file has ended (they never test for the end): ANSYS / Fluent skips to
    a closing bracket one character at a time; PLY skips blank lines; Kratos (.mdpa), Nastran and
    Tecplot skip lines until a keyword. Reads at the end give b"" as usual (a reader's own loop
    stops on one) up to AT_END times: io.TextIOWrapper, through which a text reader reads with
    read1, reads the end once per line asked for after the last one."""

    AT_END = 1000
    ends_read = 0

    def _at_end(self, data: bytes, size: int | None) -> bytes:
        if data or size == 0:
            return data
        self.ends_read += 1
        if self.ends_read > self.AT_END:
            from meshio import ReadError

            raise ReadError("the file ends where its reader expects more (truncated, or a bracket short?)")
        return data

    def read(self, size: int | None = -1) -> bytes:
        return self._at_end(super().read(size), size)

    def read1(self, size: int = -1) -> bytes:
        return self._at_end(super().read1(size), size)

    def readline(self, size: int | None = -1) -> bytes:
        return self._at_end(super().readline(size), size)


# meshio's formats read through _EndOfFileRaises (the mode its reader opens a file in), found by
# cutting a file each format's writer made at every byte (tests/test_mesh_file.py).
_LOOPS_AT_END = {"ansys": "rb", "ply": "rb", "mdpa": "rb", "nastran": "r", "tecplot": "r"}


def _meshio_format(path: Path) -> str | None:
    """The one meshio format of path's suffix; a .msh told apart by its first word (gmsh's
    ``$MeshFormat``, else ANSYS / Fluent's); None where meshio is left to choose."""
    import meshio

    suffix = path.suffix.lower()
    if suffix == ".msh":
        with open(path, "rb") as f:
            return "gmsh" if f.read(256).lstrip().startswith(b"$MeshFormat") else "ansys"
    formats = meshio.extension_to_filetypes.get(suffix, [])
    return formats[0] if len(formats) == 1 else None


def _tetgen_headers(path: Path) -> None:
    """meshio's TetGen reader skips blank and comment lines for ever when a .node or .ele file has
    no header line: raise its ReadError first."""
    from meshio import ReadError

    for part in (path.with_suffix(".node"), path.with_suffix(".ele")):
        if not part.is_file():
            raise ReadError(f"TetGen's {part.name} is missing beside it")
        with open(part, "rb") as f:
            if not any(line.strip() and not line.lstrip().startswith(b"#") for line in f):
                raise ReadError(f"{part.name} holds no header line")


def _meshio_read(path: Path):
    """meshio.read, the formats whose readers loop at the end of a cut file read through
    _EndOfFileRaises."""
    import meshio

    file_format = _meshio_format(path)
    if file_format == "tetgen":
        _tetgen_headers(path)
    mode = _LOOPS_AT_END.get(file_format or "")
    with _bounded_memory(_bounded_size(path, file_format)):
        if mode is None:
            return meshio.read(path, file_format=file_format)
        with _EndOfFileRaises(io.FileIO(path, "rb")) as f:
            if mode == "rb":
                return meshio.read(f, file_format=file_format)
            with io.TextIOWrapper(f) as text:
                return meshio.read(text, file_format=file_format)


# A read's memory beyond what the process used before it: meshio's readers allocate arrays by the
# counts a file states, so a damaged count in a file of a few hundred bytes asked for 21 GiB, which
# Linux grants and then kills the process for when it is touched. Generous for what a file of
# ``size`` bytes holds (ASCII parsed through Python lists: about 40 bytes a number of 10 or more).
def _read_memory(size: int) -> int:
    return max(2 << 30, 64 * size)


# Formats whose data may lie in other files or be compressed beyond that (HDF5, netCDF, XDMF).
_UNBOUNDED = {"xdmf", "exodus", "cgns", "med", "h5m", "hmf"}


def _bounded_size(path: Path, file_format: str | None) -> int | None:
    """The bytes a meshio read of ``path`` parses (TetGen's .node and .ele together), or None where
    its memory is left unbounded (the formats above, gzipped files, a format meshio guesses)."""
    if file_format is None or file_format in _UNBOUNDED or path.suffix.lower() == ".gz":
        return None
    if file_format == "tetgen":
        return sum(path.with_suffix(s).stat().st_size for s in (".node", ".ele"))
    return path.stat().st_size


_BOUND_LOCK = threading.Lock()  # one bounded read at a time: the bound is the process's


@contextlib.contextmanager
def _bounded_memory(size: int | None):
    """Within it (unless size is None), allocations beyond _read_memory(size) more than the
    process holds fail with a MemoryError instead of succeeding and ending in the kernel's
    out-of-memory kill. Linux only (RLIMIT_DATA counts anonymous memory since 4.7); elsewhere, or
    under a tighter bound of the user's own, nothing changes."""
    try:
        import resource
    except ImportError:  # Windows
        yield
        return
    with _BOUND_LOCK:
        used = data_segment()
        soft, hard = resource.getrlimit(resource.RLIMIT_DATA)
        limit = None if used is None or size is None else used + _read_memory(size)
        unbounded = resource.RLIM_INFINITY
        if limit is None or (soft != unbounded and soft <= limit) or (hard != unbounded and hard < limit):
            yield
            return
        resource.setrlimit(resource.RLIMIT_DATA, (limit, hard))
        try:
            yield
        finally:
            resource.setrlimit(resource.RLIMIT_DATA, (soft, hard))


def read_meshio(path, what: str = "mesh"):
    """``meshio.read(path)`` with every failure (exceptions, meshio's printed errors and its
    ``sys.exit``) turned into one MeshError naming the file and the reason."""
    path = Path(path)
    problem = file_problem(path)
    if problem:
        raise MeshError(f"{path}: {problem}")
    sink = io.StringIO()
    try:
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            return _meshio_read(path)
    except (Exception, SystemExit) as e:
        said = " ".join(sink.getvalue().split())
        reason = (
            f"{type(e).__name__}: {e}"
            if str(e).strip() and not isinstance(e, SystemExit)
            else (said or type(e).__name__)
        )
        reason = " ".join(reason.split())  # one line (meshio's messages may hold newlines)
        if isinstance(e, MemoryError):
            reason += "; a count in the file larger than what it holds?"
        raise MeshError(f"{path}: cannot read as a {what} ({reason[:300]})") from None


def check_output_file(path, what: str = "output file", mesh_format: bool = False) -> Path:
    """Check, before any work, that a file can be written at ``path``: its folder exists, is a
    folder and is writable, and ``path`` is not a folder; with ``mesh_format``, that meshio knows
    the format of its extension. Raises InputError naming the path."""
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise InputError(f"{path}: the {what} is a folder; expected a file name")
    if mesh_format:
        import meshio

        if path.suffix.lower() not in meshio.extension_to_filetypes:
            raise InputError(
                f"{path}: unknown {what} format {path.suffix!r}; expected an extension "
                "meshio writes (.obj, .stl, .ply, .off, .vtk, .vtu, .msh...)"
            )
    if not parent.exists():
        raise InputError(f"{path}: cannot write the {what}: folder {parent} does not exist")
    if not parent.is_dir():
        raise InputError(f"{path}: cannot write the {what}: {parent} is not a folder")
    _probe_folder(parent, path, what)
    if path.exists() and not os.access(path, os.W_OK):
        raise InputError(f"{path}: cannot write the {what}: the file is read-only")
    _refuse_special(path, what)
    return path


def _refuse_special(path: Path, what: str) -> None:
    """Refuse an output path that is a device, pipe or socket: the file is written under another
    name and renamed into place, which would replace /dev/null itself."""
    if file_problem(path) == NOT_REGULAR:  # (MISSING for a new one)
        raise InputError(
            f"{path}: cannot write the {what} there: not a regular file (a device, pipe or "
            "socket, which the new file would replace); expected a file name"
        )


def _new_file_mode(path: Path) -> int:
    """The permissions a written file gets: those of the file it replaces, else 0o666 less the
    process's umask (what open() gives a new file; mkstemp's temporary files are 0o600)."""
    try:
        return stat.S_IMODE(path.stat().st_mode)
    except OSError:
        return 0o666 & ~_umask()


def _umask() -> int:
    """The process's umask, read without changing it (Linux: /proc/self/status); elsewhere the
    one it had when pliant was imported."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    return _UMASK_AT_IMPORT


def _read_umask_once() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_UMASK_AT_IMPORT = _read_umask_once()


def _probe_folder(folder: Path, path: Path, what: str) -> None:
    """Create and remove a scratch file in ``folder``: the only test of writability that holds for
    root, read-only file systems and pseudo file systems alike."""
    try:
        with tempfile.TemporaryFile(dir=folder, prefix=".pliant-probe-"):
            pass
    except OSError as e:
        raise InputError(
            f"{path}: cannot write the {what}: folder {folder} is not writable ({e.strerror or e})"
        ) from None


def check_output_dir(path, what: str = "output folder") -> Path:
    """Check that ``path`` is, or can be made, a writable folder (nothing is created). Raises
    InputError naming the path and the reason."""
    path = Path(path)
    if path.exists():
        if not path.is_dir():
            raise InputError(f"{path}: the {what} is a file; expected a folder")
        _probe_folder(path, path, what)
        return path
    up = path.parent
    while not up.exists() and up != up.parent:
        up = up.parent
    if not up.is_dir():
        raise InputError(f"{path}: cannot create the {what}: {up} is a file")
    _probe_folder(up, path, what)
    return path


def make_output_dir(path, what: str = "output folder") -> Path:
    """Create the folder (and its parents); OSError becomes InputError naming it."""
    path = check_output_dir(path, what)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"{path}: cannot create the {what}: {e.strerror or e}") from None
    return path


@contextlib.contextmanager
def deferred_interrupt():
    """Hold Ctrl-C (SIGINT) and SIGTERM while a group of files is committed, so that an index never
    lists one frame fewer than was written; the interrupt is raised when the block ends. Main
    thread only (elsewhere a plain block). A signal the process ignores stays ignored: a job a
    shell started in the background ignores SIGINT (POSIX), and was interrupted by one that
    landed while a frame was written, running on through the others."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []
    held = [s for s in (signal.SIGINT, signal.SIGTERM) if signal.getsignal(s) is not signal.SIG_IGN]
    old = [signal.signal(s, lambda s, f: got.append(s)) for s in held]
    try:
        yield
    finally:
        for s, handler in zip(held, old):
            signal.signal(s, handler)
        if got:
            raise KeyboardInterrupt


def atomic_write(path, write, what: str = "file") -> Path:
    """Write a file atomically: ``write(tmp_path)`` writes a temporary file in the same folder,
    which is then renamed to ``path``. On failure nothing is left behind; OSError becomes an
    InputError naming ``path``."""
    path = Path(path)
    _refuse_special(path, what)
    suffix = "".join(path.suffixes[-1:])
    try:
        fd, tmp = tempfile.mkstemp(
            dir=path.parent if str(path.parent) else ".", prefix=f".{path.stem}.", suffix=f".tmp{suffix}"
        )
        os.close(fd)
    except OSError as e:
        raise InputError(f"{path}: cannot write the {what}: {e.strerror or e}") from None
    try:
        write(tmp)
        os.chmod(tmp, _new_file_mode(path))
        os.replace(tmp, path)
    except OSError as e:
        Path(tmp).unlink(missing_ok=True)
        raise InputError(f"{path}: cannot write the {what}: {e.strerror or e}") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write_text(path, text: str, what: str = "file") -> Path:
    """Write ``text`` to ``path`` atomically (fsync'd before the rename)."""

    def write(tmp):
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())

    return atomic_write(path, write, what)
