"""An FMU archive opened as untrusted input: bounded unpacking and names that stay inside.

An FMU is a zip archive from someone else. :func:`extract_fmu` unpacks it into a private
temporary folder (mode 0700, :func:`tempfile.mkdtemp`) under the caps of
:class:`ArchiveLimits`: the number of members, each member's and the total unpacked size
(checked on the sizes the zip headers declare *and* while streaming each member, so a zip
bomb whose headers lie stops at the cap instead of being unpacked whole), and the size of
``modelDescription.xml``. Member names that are absolute, climb out with ``..``, or are
links are refused by name. :func:`inside` checks every later path taken from the
archive's XML (source files, include directories, the model identifier) the same way.
The limits are documented in ``docs/fmu.md`` and ``docs/reliability.md``.
"""

from __future__ import annotations

import re
import shutil
import stat
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from gtmodel.errors import InputError

__all__ = ["ArchiveLimits", "extract_fmu", "inside", "plain_identifier"]

_MB = 1 << 20
#: A C identifier: what the FMI standard requires of ``modelIdentifier`` (the binary's name and the functions' prefix).
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,199}")


@dataclass(frozen=True)
class ArchiveLimits:
    """Caps on an FMU archive, checked before and while it is unpacked.

    Parameters
    ----------
    max_members : int, optional
        Number of members (files and folders) in the archive; default 10,000.
    max_member_bytes : int, optional
        Unpacked size of any one member [bytes]; default 256 MiB.
    max_total_bytes : int, optional
        Unpacked size of all members together [bytes]; default 1 GiB.
    max_description_bytes : int, optional
        Size of ``modelDescription.xml`` and ``sources/buildDescription.xml`` [bytes];
        default 8 MiB (a description of 200,000 variables is 31 MB and takes minutes to load).
    """

    max_members: int = 10_000
    max_member_bytes: int = 256 * _MB
    max_total_bytes: int = 1024 * _MB
    max_description_bytes: int = 8 * _MB

    def __post_init__(self) -> None:
        for field in ("max_members", "max_member_bytes", "max_total_bytes", "max_description_bytes"):
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
                raise InputError(f"limits.{field}: expected a positive integer, got {value!r}")


_DESCRIPTIONS = ("modelDescription.xml", "sources/buildDescription.xml")
_CHUNK = 1 << 16


def _member_error(path: Path, name: str, why: str) -> InputError:
    return InputError(f"{path}: archive member {name[:200]!r} {why}; the FMU is refused")


def _check_name(path: Path, info: zipfile.ZipInfo) -> PurePosixPath:
    name = info.filename
    rel = PurePosixPath(name.replace("\\", "/"))
    if not name or rel.is_absolute() or re.match(r"^[A-Za-z]:", name) or ".." in rel.parts or "\0" in name:
        raise _member_error(path, name, "is not a plain relative name inside the archive (absolute or '..')")
    mode = info.external_attr >> 16
    if stat.S_IFMT(mode) and not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):  # a type set, and not file/folder
        raise _member_error(path, name, "is a link or special file")
    return rel


def _copy_capped(path: Path, zf: zipfile.ZipFile, info: zipfile.ZipInfo, target: Path, cap: int, total: list[int],
                 limits: ArchiveLimits) -> None:
    """Stream one member to ``target``, counting the bytes actually produced (a repeated name
    overwrites the earlier copy, as ``zipfile.extractall`` does; both count towards the total)."""
    written = 0
    with zf.open(info) as src, open(target, "wb") as dst:
        while True:
            chunk = src.read(_CHUNK)
            if not chunk:
                break
            written += len(chunk)
            total[0] += len(chunk)
            if written > cap:
                raise _member_error(path, info.filename, f"unpacks to more than {cap} bytes (its cap)")
            if total[0] > limits.max_total_bytes:
                raise InputError(f"{path}: the archive unpacks to more than {limits.max_total_bytes} bytes "
                                 "(limits.max_total_bytes); the FMU is refused")
            dst.write(chunk)


def _central_directory(path: Path) -> tuple[int, int] | None:
    """(entries, bytes) of the archive's central directory from its end record, read before
    ``zipfile`` loads every entry into memory; None when there is no end record."""
    with open(path, "rb") as fh:
        fh.seek(0, 2)
        size = fh.tell()
        fh.seek(max(0, size - (1 << 16) - 22))
        tail = fh.read()
        at = tail.rfind(b"PK\x05\x06")
        if at < 0 or len(tail) < at + 22:
            return None
        entries = int.from_bytes(tail[at + 10:at + 12], "little")
        cd_bytes = int.from_bytes(tail[at + 12:at + 16], "little")
        loc = at - 20
        if (entries == 0xFFFF or cd_bytes == 0xFFFFFFFF) and loc >= 0 and tail[loc:loc + 4] == b"PK\x06\x07":
            fh.seek(int.from_bytes(tail[loc + 8:loc + 16], "little"))
            record = fh.read(56)
            if record[:4] == b"PK\x06\x06" and len(record) == 56:
                entries = int.from_bytes(record[32:40], "little")
                cd_bytes = int.from_bytes(record[40:48], "little")
        return entries, cd_bytes


def extract_fmu(path: Path, limits: ArchiveLimits | None = None) -> Path:
    """Unpack an FMU into a new private temporary folder, refusing what breaks the limits.

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file.
    limits : ArchiveLimits, optional
        The caps; default :class:`ArchiveLimits()`.

    Returns
    -------
    pathlib.Path
        The folder (mode 0700); the caller removes it (``shutil.rmtree``).

    Raises
    ------
    InputError
        Naming the file and, where one is at fault, the member: not a zip archive, too many
        members, a member or the whole larger than its cap (declared or while unpacking),
        ``modelDescription.xml`` larger than ``max_description_bytes``, a member name that
        is absolute, climbs out with ``..`` or is a link. Nothing is left on disk then.
    """
    limits = limits or ArchiveLimits()
    folder = Path(tempfile.mkdtemp(prefix="gtmodel_fmu_import_"))
    root = folder.resolve()
    try:
        directory = _central_directory(path)  # before zipfile reads every entry into memory
        if directory is not None and (directory[0] > limits.max_members or directory[1] > limits.max_members * 4096):
            raise InputError(f"{path}: the archive declares {directory[0]} members ({directory[1]} bytes of directory), more "
                             f"than {limits.max_members} (limits.max_members); the FMU is refused")
        with zipfile.ZipFile(path) as zf:
            infos = zf.infolist()
            if len(infos) > limits.max_members:
                raise InputError(f"{path}: the archive has {len(infos)} members, more than {limits.max_members} "
                                 "(limits.max_members); the FMU is refused")
            declared = 0
            for info in infos:
                rel = _check_name(path, info)
                cap = limits.max_description_bytes if rel.as_posix() in _DESCRIPTIONS else limits.max_member_bytes
                if info.file_size > cap:
                    raise _member_error(path, info.filename, f"declares {info.file_size} bytes unpacked, more than its cap of {cap}")
                declared += info.file_size
            if declared > limits.max_total_bytes:
                raise InputError(f"{path}: the archive declares {declared} bytes unpacked, more than "
                                 f"{limits.max_total_bytes} (limits.max_total_bytes); the FMU is refused")
            total = [0]
            for info in infos:
                rel = _check_name(path, info)
                target = root.joinpath(*rel.parts)
                if not target.resolve().is_relative_to(root):
                    raise _member_error(path, info.filename, "resolves outside the extraction folder")
                if info.is_dir():
                    target.mkdir(parents=True, exist_ok=True)
                    continue
                target.parent.mkdir(parents=True, exist_ok=True)
                if target.is_dir():
                    raise _member_error(path, info.filename, "is a file and a folder")
                cap = limits.max_description_bytes if rel.as_posix() in _DESCRIPTIONS else limits.max_member_bytes
                _copy_capped(path, zf, info, target, cap, total, limits)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, EOFError, OSError, RuntimeError) as exc:
        shutil.rmtree(folder, ignore_errors=True)
        raise InputError(f"{path}: not an FMU (corrupt archive: {type(exc).__name__}: {str(exc)[:200]})") from None
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return folder


def inside(path: Path, base: Path, name: str | None, what: str) -> Path:
    """``base / name`` for a relative name from the archive's XML that stays inside ``base``.

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file (for the message).
    base : pathlib.Path
        The folder the name is relative to (e.g. the unpacked ``sources``).
    name : str or None
        The name as written in the XML.
    what : str
        What the name is (e.g. ``"buildDescription SourceFile"``), for the message.

    Returns
    -------
    pathlib.Path
        The resolved path, inside ``base`` (symbolic links resolved first).

    Raises
    ------
    InputError
        Naming the file, ``what`` and the name: empty, absolute, or resolving outside ``base``.
    """
    if not name or "\0" in name:
        raise InputError(f"{path}: {what} has no name")
    rel = PurePosixPath(name.replace("\\", "/"))
    base = base.resolve()
    target = base.joinpath(*rel.parts).resolve()
    if rel.is_absolute() or re.match(r"^[A-Za-z]:", name) or not target.is_relative_to(base):
        raise InputError(f"{path}: {what} {name[:200]!r} is not a relative name inside the FMU's "
                         f"{base.name}/ folder; the FMU is refused")
    return target


def plain_identifier(path: Path, ident: str, where: str) -> str:
    """Check a ``modelIdentifier``: a C identifier, as the FMI standard requires (no path).

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file (for the message).
    ident : str
        The attribute's value.
    where : str
        The element it is read from (``"ModelExchange"``, ``"buildDescription BuildConfiguration"``).

    Returns
    -------
    str
        ``ident``, unchanged.

    Raises
    ------
    InputError
        ``ident`` is not ``[A-Za-z_][A-Za-z0-9_]*`` (at most 200 characters): it names the file,
        the element and the value.
    """
    if not _IDENTIFIER.fullmatch(ident or ""):
        raise InputError(f"{path}: {where} modelIdentifier {ident[:200]!r} is not a C identifier "
                         "(letters, digits, '_'; the FMI standard's rule, no path); the FMU is refused")
    return ident
