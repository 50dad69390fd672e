"""Writing results so that nobody ever sees half a file, or a folder that mixes two runs.

* Files: :func:`atomic_file` (and :func:`write_text_atomic`) write into a temporary file with a unique name
  (:func:`tempfile.mkstemp`) in the target's folder and rename it over the target with :func:`os.replace`. A
  reader sees the old file or the new one, concurrent writers never share a temporary file, and on any failure
  (Ctrl-C included) the temporary file is removed and the target left as it was.
* Folders: :func:`staged_folder` hands out a fresh staging folder beside the target; when the block completes,
  the staging folder is renamed to the target (the folder it replaces, if any, is moved aside and removed). The
  target is therefore always missing or one complete run's folder, and never keeps files of an earlier run.
* Checks before the work: :func:`check_output_file` and :func:`check_output_folder` raise
  :class:`~convexguid.errors.OutputError` (one line) for a target that cannot be written, so a long solve is
  never thrown away at the end for a typo in a path. They create nothing.
"""

from __future__ import annotations

import os
import shutil
import stat
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import IO

from convexguid.errors import OutputError

PUBLISH_ATTEMPTS = 50
"""How often :func:`staged_folder` retries renaming its folder into place while other runs replace it too."""


def describe(exc: OSError) -> str:
    """An OS error as a short reason (``Permission denied``), without the repeated file name."""
    return exc.strerror or str(exc) or type(exc).__name__


def _umask() -> int:
    """The process's file-creation mask (read from ``/proc`` where possible, so it is never changed)."""
    with suppress(OSError, ValueError):
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _is_special(path: Path) -> bool:
    """True for an existing target that is neither a regular file nor a folder (``/dev/null``, a pipe)."""
    with suppress(OSError):
        mode = os.stat(path).st_mode
        return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))
    return False


@contextmanager
def atomic_file(path: str | os.PathLike[str], mode: str = "w", **open_kwargs) -> Iterator[IO]:
    """Open a temporary file beside ``path`` for writing; on success rename it over ``path``.

    ``mode`` and ``open_kwargs`` are those of :func:`open` (``"w"`` text, ``"wb"`` binary). The new file gets the
    permissions of the file it replaces, or those a plain :func:`open` would give. A symbolic link is followed
    (its target is replaced, the link kept); a device or pipe such as ``/dev/null`` is written directly.
    The folder must exist.
    """
    target = Path(os.path.realpath(path))
    if _is_special(target):
        with open(target, mode, **open_kwargs) as fh:
            yield fh
        return
    fd, tmp_name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    try:
        try:
            fh = os.fdopen(fd, mode, **open_kwargs)
        except BaseException:
            os.close(fd)
            raise
        with fh:
            yield fh
        try:
            permissions = stat.S_IMODE(os.stat(target).st_mode)
        except FileNotFoundError:
            permissions = 0o666 & ~_umask()
        os.chmod(tmp_name, permissions)
        os.replace(tmp_name, target)
    except BaseException:
        with suppress(OSError):
            os.unlink(tmp_name)
        raise


def write_text_atomic(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` through :func:`atomic_file`, creating missing parent folders."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_file(path, "w", encoding="utf-8") as fh:
        fh.write(text)


def rescue_copy(text: str, name: str) -> Path | None:
    """Write ``text`` to a new file in the system's temporary folder (``convexguid-<stem>-*.<suffix>`` after
    ``name``), for results whose intended place could not be written; its path, or None if that fails too."""
    stem, _, suffix = name.rpartition(".")
    try:
        fd, rescued = tempfile.mkstemp(prefix=f"convexguid-{stem or suffix}-", suffix=f".{suffix}" if stem else "")
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError:
        return None
    return Path(rescued)


@contextmanager
def staged_folder(target: str | os.PathLike[str], *, replace: bool) -> Iterator[Path]:
    """A fresh, empty staging folder beside ``target``, renamed to ``target`` when the block completes.

    Missing parent folders are created. If the block raises, the staging folder is removed and ``target`` is
    untouched. At the rename, an existing non-empty ``target`` is replaced only with ``replace`` (it is moved
    aside and removed); without it, or when the rename keeps failing, :class:`~convexguid.errors.OutputError`
    says where the staged outputs were left. Concurrent runs into the same target each publish a complete
    folder; the last one to finish is what remains.
    """
    final = Path(os.path.realpath(target))
    final.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(dir=final.parent, prefix=f".{final.name}.staging-"))
    try:
        yield staging
        os.chmod(staging, 0o777 & ~_umask())
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    _publish(staging, final, replace=replace)


def _publish(staging: Path, target: Path, *, replace: bool) -> None:
    """Rename ``staging`` to ``target``, moving a non-empty ``target`` aside first if ``replace`` allows."""
    kept = f"the outputs of this run are in {staging}"
    reason = "other runs kept replacing it"
    for _ in range(PUBLISH_ATTEMPTS):
        try:
            os.rename(staging, target)  # atomic; fails while target is a non-empty folder (or a file)
            return
        except OSError as exc:
            reason = describe(exc)
            if target.exists() and not target.is_dir():
                raise OutputError(f"{target}: exists and is not a folder; {kept}") from exc
            if _has_entries(target):
                if not replace:
                    raise OutputError(f"{target}: the folder is not empty (filled by another run meanwhile?) and "
                                      f"may not be replaced without --overwrite; {kept}") from exc
                _discard(target)
            elif target.exists():
                with suppress(OSError):
                    os.rmdir(target)  # an empty folder in the way (where a rename does not replace one)
    raise OutputError(f"{target}: cannot move the outputs into place ({reason}); {kept}")


def _discard(folder: Path) -> None:
    """Move ``folder`` into a fresh hidden folder beside it (one atomic rename) and remove it from there."""
    trash = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}.replaced-"))
    try:
        os.rename(folder, trash / folder.name)
    except FileNotFoundError:
        pass  # another run moved it first
    finally:
        shutil.rmtree(trash, ignore_errors=True)


def _has_entries(folder: Path) -> bool:
    try:
        with os.scandir(folder) as entries:
            return next(entries, None) is not None
    except (FileNotFoundError, NotADirectoryError):
        return False


def _nearest_existing(path: Path) -> Path:
    """``path`` or its closest ancestor that exists."""
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _probe(folder: Path, where: str) -> None:
    """Create and remove a file in ``folder``; :class:`OutputError` naming ``where`` if that fails."""
    try:
        fd, name = tempfile.mkstemp(dir=folder, prefix=".convexguid-probe-")
    except OSError as exc:
        raise OutputError(f"{where}: cannot write in {folder} ({describe(exc)})") from exc
    os.close(fd)
    os.unlink(name)


def check_output_file(path: str | os.PathLike[str], what: str) -> None:
    """Raise :class:`OutputError` unless the file ``path`` (``what`` it is, for the message) can be written.

    The folder must exist and take new files; ``path`` must not be a folder. Nothing is left behind.
    """
    target = Path(os.path.realpath(path))
    where = f"{path}: cannot write the {what} here"
    if target.is_dir():
        raise OutputError(f"{where}: it is a folder; name a file")
    if _is_special(target):
        if not os.access(target, os.W_OK):
            raise OutputError(f"{where}: not writable")
        return
    folder = target.parent
    if not folder.exists():
        raise OutputError(f"{where}: folder {folder} does not exist")
    if not folder.is_dir():
        raise OutputError(f"{where}: {folder} is not a folder")
    _probe(folder, where)


def check_output_folder(path: str | os.PathLike[str], *, overwrite: bool, keep: Iterable[str | os.PathLike[str]] = (),
                        ) -> None:
    """Raise :class:`OutputError` unless :func:`staged_folder` can publish an output folder at ``path``.

    ``path`` must be a folder or missing (missing parents are created later), and its parent must take new
    entries. A non-empty folder needs ``overwrite`` (``--overwrite``: it is replaced, its contents removed). A
    folder that is or holds the working directory or one of the paths in ``keep`` (e.g. the problem file) is
    refused: publishing replaces the whole folder. Nothing is created.
    """
    target = Path(os.path.realpath(path))
    where = f"{path}: cannot write the output folder here"
    if target.exists() and not target.is_dir():
        raise OutputError(f"{where}: it exists and is not a folder")
    for kept in (Path.cwd(), *keep):
        kept = Path(os.path.realpath(kept))
        if kept == target or target in kept.parents:
            raise OutputError(f"{where}: replacing it would remove {kept}; name a folder of its own")
    if _has_entries(target) and not overwrite:
        raise OutputError(f"{path}: the output folder is not empty; give --overwrite to replace it (its contents "
                          "are removed) or name a new folder")
    ancestor = _nearest_existing(target.parent)
    if not ancestor.is_dir():
        raise OutputError(f"{where}: {ancestor} is not a folder")
    _probe(ancestor, where)
