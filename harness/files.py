"""Output files written whole: single files atomically, sets of files all or nothing.

Single files (:func:`write_csv`, :func:`write_text`, :func:`save_figure`) are
written to a temporary file beside the destination, then renamed over it: the
destination holds the previous content or the new one, never a part.

Sets of files (:class:`OutputSet`) replace the previous set whole, or not at all.

A command's outputs (CSV, PNG, ``summary.txt``, FMUs, an HTML report) have
fixed names in a folder that may hold other files.  No file system renames
several files at once, so :class:`OutputSet` makes the switch in three steps:

1. **Staging.**  Every file is written into ``<base>/.djl-fmu-tmp-XXXX/new/``,
   a fresh folder on the same file system as the destinations.  Nothing in
   ``<base>`` changes: an interruption here leaves the previous files as they
   were, and the staging folder is removed.
2. **Swap.**  Once every file is written, a journal (the names, and the device
   and inode of each new file) is written, then, file after file, the previous
   file is hard-linked into ``old/`` (copied where links are not possible) and
   the new one renamed over it (``os.replace``: each destination holds a whole
   file at every moment, the previous or the new one).  SIGINT, SIGTERM and
   SIGHUP are held back during the swap and delivered after it.  If the swap
   raises (a full disk, a permission), every destination that holds a new file
   is put back: the backup renamed over it, or the new file removed where
   there was none -- the previous set, byte for byte.
3. **Commit.**  The journal is deleted, then the staging folder.

A process killed during the swap (SIGKILL, a crash) leaves the journal: the
next :class:`OutputSet` opened on the same folder (any ``djl-fmu`` command
writing there) rolls the swap back before anything else.  Staging folders are
locked (``flock``) by their live process; an unlocked one is stale and is
removed.  The swaps of concurrent processes on one folder are serialised by a
lock on the folder itself.  Nothing is ``fsync``-ed: a power cut or an OS
crash may lose the last writes.

Files of the previous set that the new set does not include are left alone,
as are the other files of the folder.
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import json
import os
import shutil
import signal
import stat
import tempfile
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path, PurePosixPath
from types import FrameType, TracebackType
from typing import Any

import numpy as np

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: no locking, stale folders ignored
    fcntl = None  # type: ignore[assignment]

__all__ = ["FIGURE_CACHE_SIZE", "TMP_PREFIX", "OutputSet", "Terminated", "figure_digest",
           "recover_stale", "save_figure",
           "signals_deferred", "sigterm_raises", "write_csv", "write_set", "write_text"]

TMP_PREFIX = ".djl-fmu-tmp-"
"""Name prefix of the staging folders (in the output folder)."""

JOURNAL = "journal.json"
"""The swap journal, in the staging folder while the swap runs."""

Entry = tuple[str, int, int]
"""One file of a swap: name relative to the base folder, device and inode of the new file."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised as an exception (by :func:`sigterm_raises`) so that clean-ups run."""


# ----------------------------------------------------------------- signals

_HELD = tuple(s for s in (getattr(signal, n, None) for n in ("SIGINT", "SIGTERM", "SIGHUP"))
              if s is not None)


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Hold SIGINT, SIGTERM and SIGHUP back while the block runs; deliver them after it.

    Only in the main thread (elsewhere the block runs unprotected: Python
    delivers signals to the main thread).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []

    def hold(signum: int, _frame: FrameType | None) -> None:
        got.append(signum)

    old: dict[int, Any] = {}
    for s in _HELD:
        prev = signal.getsignal(s)
        if prev is None:  # installed outside Python: cannot be put back
            continue
        signal.signal(s, hold)
        old[s] = prev
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        for s in dict.fromkeys(got):
            signal.raise_signal(s)


@contextlib.contextmanager
def sigterm_raises() -> Iterator[None]:
    """Turn SIGTERM into :class:`Terminated` while the block runs (main thread only).

    Python's default is to die at once, skipping every ``finally``: temporary
    folders would stay.  A forked worker process inherits the handler; there it
    dies of the signal, as by default.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    owner = os.getpid()

    def handler(signum: int, _frame: FrameType | None) -> None:
        if os.getpid() != owner:
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)
            return
        raise Terminated(f"signal {signum}")

    prev = signal.getsignal(signal.SIGTERM)
    if prev is None:
        yield
        return
    signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, prev)


# ----------------------------------------------------------------- locks

def _open_dir(path: Path) -> int | None:
    try:
        return os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return None


def _flock(fd: int, blocking: bool) -> bool | None:
    """Lock ``fd`` exclusively: True if locked, False if another holds it, None if no locking."""
    if fcntl is None:  # pragma: no cover - not POSIX
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
    except BlockingIOError:
        return False
    except OSError:  # e.g. a file system without locks
        return None
    return True


@contextlib.contextmanager
def _dir_locked(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on the folder ``path`` (where locks are available)."""
    fd = _open_dir(path)
    try:
        if fd is not None:
            _flock(fd, blocking=True)
        yield
    finally:
        if fd is not None:
            os.close(fd)


# ----------------------------------------------------------------- names and folders

def _safe_name(name: str | os.PathLike[str]) -> str:
    """Check an output name: relative, inside the base folder, not a staging folder."""
    p = PurePosixPath(Path(name).as_posix())
    if (p.is_absolute() or not p.parts or any(x in ("..", ".", "") for x in p.parts)
            or p.parts[0].startswith(TMP_PREFIX)):
        raise ValueError(f"{name!r}: an output name must be a relative path inside the folder")
    return p.as_posix()


def _make_dirs(path: Path) -> list[Path]:
    """Create ``path`` and its missing parents; return those created, outermost first."""
    missing: list[Path] = []
    p = path
    while not p.exists() and p.parent != p:
        missing.append(p)
        p = p.parent
    created: list[Path] = []
    for d in reversed(missing):
        try:
            d.mkdir()
        except FileExistsError:
            continue
        created.append(d)
    return created


def _remove_empty(dirs: list[Path]) -> None:
    for d in reversed(dirs):
        try:
            d.rmdir()
        except OSError:
            pass


# ----------------------------------------------------------------- journal

def _write_journal(tmp: Path, entries: list[Entry]) -> None:
    part = tmp / (JOURNAL + ".part")
    part.write_text(json.dumps({"format": 1, "files": [list(e) for e in entries]}),
                    encoding="utf-8")
    os.replace(part, tmp / JOURNAL)


def _read_journal(tmp: Path) -> list[Entry] | None:
    """Return the journal's entries; None if there is none or it is not one of ours."""
    try:
        data = json.loads((tmp / JOURNAL).read_text(encoding="utf-8"))
        entries = [(_safe_name(n), int(d), int(i)) for n, d, i in data["files"]]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return entries


def _rollback(base: Path, tmp: Path, entries: list[Entry]) -> None:
    """Put the previous files back wherever a destination holds a new file; drop the journal.

    A destination that does not hold the new file (never swapped, or changed
    since) is left alone, so rolling back twice is harmless.
    """
    for name, dev, ino in reversed(entries):
        dest = base / name
        try:
            st = os.lstat(dest)
        except FileNotFoundError:
            continue
        if (st.st_dev, st.st_ino) != (dev, ino):
            continue
        old = tmp / "old" / name
        if os.path.lexists(old):
            os.replace(old, dest)
        else:
            os.unlink(dest)
    (tmp / JOURNAL).unlink(missing_ok=True)


def _swap_one(base: Path, tmp: Path, name: str, created: list[Path]) -> None:
    """Back the previous ``name`` up into ``old/`` (a hard link), rename the new one over it."""
    dest = base / name
    if os.path.lexists(dest):
        old = tmp / "old" / name
        old.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.link(dest, old, follow_symlinks=False)
        except OSError:
            shutil.copy2(dest, old, follow_symlinks=False)
    else:
        created += _make_dirs(dest.parent)
    os.replace(tmp / "new" / name, dest)


def recover_stale(base: str | os.PathLike[str], keep: Path | None = None) -> None:
    """Roll back and remove the staging folders left in ``base`` by killed processes.

    A folder still locked by its process is left alone, as is one whose
    journal cannot be rolled back (tried again next time).  Without ``flock``
    (not POSIX) nothing is removed.
    """
    base = Path(base)
    try:
        found = sorted(base.glob(TMP_PREFIX + "*"))
    except OSError:
        return
    for d in found:
        if d == keep or d.is_symlink() or not d.is_dir():
            continue
        fd = _open_dir(d)
        if fd is None:
            continue
        try:
            if _flock(fd, blocking=False) is not True:
                continue  # alive, or cannot tell
            if (d / JOURNAL).exists():
                entries = _read_journal(d)
                if entries is None:
                    continue  # not a journal of ours: left alone
                try:
                    _rollback(base, d, entries)
                except OSError:
                    continue
            shutil.rmtree(d, ignore_errors=True)
        finally:
            os.close(fd)


# ----------------------------------------------------------------- the set

class OutputSet:
    """Files written into a staging folder, then swapped into ``base`` together.

    Parameters
    ----------
    base : path-like
        The output folder (created, with its parents, when the set is opened;
        removed again if the set is not committed and it stayed empty).

    Examples
    --------
    >>> with OutputSet("out") as o:                      # doctest: +SKIP
    ...     o.path("a.csv").write_text("a")
    ...     o.path("b.csv").write_text("b")
    ...     written = o.commit()       # out/a.csv and out/b.csv, both or neither

    Leaving the ``with`` block without :meth:`commit` (an exception, Ctrl-C)
    discards the staged files; the folder is as it was.
    """

    def __init__(self, base: str | os.PathLike[str]) -> None:
        self.base = Path(base)
        self.names: list[str] = []
        self.tmp: Path | None = None
        self.committed = False
        self._fd: int | None = None
        self._created: list[Path] = []
        self._keep = False

    def __enter__(self) -> OutputSet:
        try:
            self._created = _make_dirs(self.base)
            if not self.base.is_dir():
                raise NotADirectoryError(f"{self.base} is not a directory")
            with _dir_locked(self.base):
                recover_stale(self.base)
                self.tmp = Path(tempfile.mkdtemp(prefix=TMP_PREFIX, dir=self.base))
                self._fd = _open_dir(self.tmp)
                if self._fd is not None:
                    _flock(self._fd, blocking=False)
            (self.tmp / "new").mkdir()
        except BaseException:
            with signals_deferred():
                self._cleanup()
            raise
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        with signals_deferred():
            self._cleanup()

    def _cleanup(self) -> None:
        if self.tmp is not None and not self._keep:
            shutil.rmtree(self.tmp, ignore_errors=True)
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
        if not self.committed:
            _remove_empty(self._created)

    def path(self, name: str | os.PathLike[str]) -> Path:
        """Where to write the output ``name`` (relative to ``base``, e.g. ``"X.csv"``).

        The file must exist when :meth:`commit` runs; its parent folders are
        created in the staging folder.
        """
        if self.tmp is None or self.committed:
            raise RuntimeError("the output set is not open")
        rel = _safe_name(name)
        if rel not in self.names:
            self.names.append(rel)
        p = self.tmp / "new" / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        return p

    def final(self, name: str | os.PathLike[str]) -> Path:
        """Where the output ``name`` will be once committed."""
        return self.base / _safe_name(name)

    def commit(self) -> list[Path]:
        """Swap the staged files into ``base``; return their final paths, in :meth:`path` order.

        Raises
        ------
        OSError
            A staged file is missing, a destination is a folder, or a rename
            failed: the previous files are back in place (see the module).
        """
        if self.tmp is None or self.committed:
            raise RuntimeError("the output set is not open")
        entries: list[Entry] = []
        for name in self.names:
            src = self.tmp / "new" / name
            try:
                st = os.lstat(src)
            except FileNotFoundError:
                raise FileNotFoundError(f"{self.base / name} was not written") from None
            if not stat.S_ISREG(st.st_mode):
                raise OSError(f"{self.base / name}: not a regular file")
            dest = self.base / name
            if dest.is_dir():
                raise IsADirectoryError(f"{dest} is a directory")
            entries.append((name, st.st_dev, st.st_ino))
        with _dir_locked(self.base), signals_deferred():
            _write_journal(self.tmp, entries)
            created: list[Path] = []
            try:
                for name, _dev, _ino in entries:
                    _swap_one(self.base, self.tmp, name, created)
            except BaseException:
                try:
                    _rollback(self.base, self.tmp, entries)
                except OSError:
                    self._keep = True  # the journal stays: the next run rolls back
                else:
                    _remove_empty(created)
                raise
            (self.tmp / JOURNAL).unlink()
            self.committed = True
        return [self.base / n for n in self.names]


def write_set(base: str | os.PathLike[str], write: Callable[[OutputSet], None]) -> list[Path]:
    """Open an :class:`OutputSet` on ``base``, let ``write`` fill it, commit; return the paths."""
    with OutputSet(base) as o:
        write(o)
        return o.commit()


# ------------------------------------------------------------- single files


def _umask_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


@contextlib.contextmanager
def _replacing(path: Path, mode: str, **open_kw: Any) -> Iterator[Any]:
    """Open a temporary file beside ``path``; once the block ends, rename it over ``path``.

    The temporary file has a unique name (concurrent writers do not collide) and is
    removed if the block fails or is interrupted: ``path`` holds the previous contents
    or the new ones, never a part.
    """
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, mode, **open_kw) as fh:
            yield fh
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_csv(path: str | os.PathLike[str], rows: Sequence[Mapping[str, Any]]) -> Path:
    """Write dict rows as CSV atomically (temporary file, then rename).

    Floats are written with 10 significant digits.

    Parameters
    ----------
    path : path-like
        Destination.
    rows : sequence of mapping
        Rows; the columns are the keys of the first row.

    Returns
    -------
    Path
    """
    path = Path(path)
    with _replacing(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]) if rows else [])
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    return path


def write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write a text file atomically (a temporary file beside it, then rename); return its path.

    The temporary file has a unique name (concurrent writers do not collide) and is
    removed if writing fails or is interrupted: ``path`` holds the previous text or
    the new one, never a part.
    """
    path = Path(path)
    with _replacing(path, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)
    return path


def write_mat(path: str | os.PathLike[str], variables: Mapping[str, Any]) -> Path:
    """Write a MATLAB file (:func:`scipy.io.savemat`, format 5) atomically; return its path.

    ``variables`` maps variable names to arrays, strings or dicts (MATLAB structs); a
    temporary file beside ``path`` is renamed over it once complete.
    """
    from scipy.io import savemat  # deferred: scipy is heavy to import

    path = Path(path)
    with _replacing(path, "wb") as fh:
        savemat(fh, dict(variables), long_field_names=True, do_compression=True,
                oned_as="column")
    return path


def _artist_state(a: Any) -> list[Any]:
    """Return what a matplotlib artist draws, for :func:`figure_digest` (data as bytes)."""
    out: list[Any] = [type(a).__name__, a.get_visible(), a.get_alpha(), a.get_zorder(),
                      a.get_clip_on()]
    for name in ("get_text", "get_position", "get_fontsize", "get_fontweight", "get_rotation",
                 "get_horizontalalignment", "get_verticalalignment", "get_color",
                 "get_linewidth", "get_linestyle", "get_marker", "get_markersize",
                 "get_drawstyle", "get_markerfacecolor", "get_markeredgecolor",
                 "get_facecolor", "get_edgecolor", "get_hatch", "get_xlim", "get_ylim",
                 "get_xscale", "get_yscale", "get_sizes", "get_linewidths", "get_cmap",
                 "get_clim", "get_extent"):
        f = getattr(a, name, None)
        if f is None:
            continue
        try:
            v = f()
        except (TypeError, ValueError, AttributeError, NotImplementedError):
            continue
        if name == "get_cmap":
            v = getattr(v, "name", None)
        elif isinstance(v, np.ndarray):
            v = v.tobytes()
        out.append((name, v))
    for name in ("get_xydata", "get_offsets", "get_array"):
        f = getattr(a, name, None)
        v = f() if f is not None else None
        if v is not None:
            out.append((name, np.ma.getdata(np.asarray(v, dtype=float)).tobytes()))
    if hasattr(a, "get_path") and hasattr(a, "get_patch_transform"):  # patches: their shape
        out.append(a.get_path().vertices.tobytes())
        out.append(a.get_patch_transform().get_matrix().tobytes())
    if hasattr(a, "get_paths"):
        out.extend(p.vertices.tobytes() for p in a.get_paths())
    if hasattr(a, "get_position") and hasattr(a, "get_subplotspec"):  # axes: where they are
        out.append(a.get_position(original=True).bounds)
    if hasattr(a, "get_major_ticks"):  # an axis: its tick settings (the ticks follow)
        out.append(sorted((k, repr(v)) for k, v in a._major_tick_kw.items()))
        out.append(sorted((k, repr(v)) for k, v in a._minor_tick_kw.items()))
        out.append((type(a.get_major_locator()).__name__, type(a.get_major_formatter()).__name__,
                    type(a.get_minor_locator()).__name__))
    return out


def _drawn(a: Any) -> Iterator[Any]:
    """Yield an artist and what it draws, depth first; an axis' ticks are not made.

    The ticks of an axis follow from its limits, scale, locator, formatter and
    tick settings (all in its parent's and its own state); asking an axis for
    its children would create them, the most costly part of a figure.
    """
    yield a
    if hasattr(a, "get_major_ticks"):
        yield a.label
        return
    for c in a.get_children():
        yield from _drawn(c)


def figure_digest(fig: Any, dpi: int, salt: str = "") -> str:
    """Return a digest of what a matplotlib figure draws: equal digests, equal PNG files.

    Every artist of the figure contributes its type and what it draws (data,
    text, colours, styles, limits, scales, tick settings), with the figure size,
    ``dpi``, matplotlib's version and rcParams, and ``salt`` (e.g. a digest of
    the code that made the figure).
    """
    import matplotlib  # deferred: matplotlib is heavy to import

    h = hashlib.sha256()
    h.update(repr((salt, matplotlib.__version__, dpi, tuple(fig.get_size_inches()),
                   fig.subplotpars.left, fig.subplotpars.right, fig.subplotpars.top,
                   fig.subplotpars.bottom, fig.subplotpars.wspace, fig.subplotpars.hspace,
                   sorted((k, repr(v)) for k, v in matplotlib.rcParams.items()))).encode())
    for a in _drawn(fig):
        for item in _artist_state(a):
            h.update(item if isinstance(item, bytes) else repr(item).encode())
    return h.hexdigest()


def save_figure(fig: Any, path: str | os.PathLike[str], dpi: int = 110, *,
                cache: str | os.PathLike[str] | None = None, salt: str = "") -> Path:
    """Save a matplotlib figure atomically (temporary file, then rename) and close it.

    With ``cache`` (a folder), a figure drawing what one saved before draws
    (:func:`figure_digest`, with ``salt``) is not rendered again: its PNG is
    copied from the folder, which keeps the last :data:`FIGURE_CACHE_SIZE`.
    """
    import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        cached = None
        if cache is not None:
            cached = Path(cache) / f"{figure_digest(fig, dpi, salt)}{path.suffix}"
        if cached is not None and cached.is_file():
            shutil.copyfile(cached, tmp)
            with contextlib.suppress(OSError):
                os.utime(cached)  # recently used: kept
        else:
            # PNG level 1: a third of the encoding time of the default, files ~15 % larger
            fig.savefig(tmp, dpi=dpi, pil_kwargs={"compress_level": 1})
            if cached is not None:
                _keep_figure(Path(tmp), cached)
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    finally:
        plt.close(fig)
    return path


FIGURE_CACHE_SIZE = 64
"""Figures a :func:`save_figure` cache folder keeps (the least recently used go)."""


def _keep_figure(src: Path, dest: Path) -> None:
    """Copy a rendered figure into its cache folder (atomically); drop the oldest ones."""
    try:
        dest.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".fig.", dir=dest.parent)
        os.close(fd)
        try:
            shutil.copyfile(src, tmp)
            os.replace(tmp, dest)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        kept = sorted(dest.parent.glob(f"*{dest.suffix}"), key=lambda p: p.stat().st_mtime)
        for old in kept[:-FIGURE_CACHE_SIZE]:
            old.unlink(missing_ok=True)
    except OSError:  # a read-only or full cache: rendered again next time
        pass
