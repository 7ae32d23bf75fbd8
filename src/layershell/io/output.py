"""Result files written safely: atomic replacement, permissions from the umask, appended CSV rows.

Every whole file goes through :func:`atomic_write`: it is written under a temporary name in the
same folder and renamed into place (:func:`os.replace`), so a reader or a killed writer never
sees a partial file. The file gets the mode an ordinary ``open()`` would give it (``0666`` less
the umask, 0644 normally), not the 0600 of :func:`tempfile.mkstemp`. Files that grow by one row
per load step are appended to (:class:`AppendCsv`), one complete line per ``write``.
"""
from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from pathlib import Path


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


#: mode of new files: 0666 less the process umask (read once at import: os.umask is process-wide)
FILE_MODE = 0o666 & ~_umask()


def atomic_write(path: Path, write) -> None:
    """Call ``write(tmp_path)`` on a temporary file next to ``path``, then rename it into place,
    so that readers never see a partial file. The file's mode follows the umask."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name[:40]}.", suffix=".tmp")
    os.close(fd)
    try:
        os.chmod(tmp, FILE_MODE)
        write(Path(tmp))
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_text(path: Path, text: str) -> None:
    atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def write_json(path: Path, data) -> None:
    atomic_write_text(path, json.dumps(data, indent=2, default=float) + "\n")


def csv_line(row: list) -> str:
    """One CSV line (floats with 10 significant digits), as :func:`write_csv` writes it."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([f"{v:.10g}" if isinstance(v, float) else v for v in row])
    return buf.getvalue()


def csv_text(header: list[str], rows: list[list]) -> str:
    return csv_line(header) + "".join(csv_line(r) for r in rows)


def write_csv(path: Path, header: list[str], rows: list[list]) -> None:
    atomic_write_text(path, csv_text(header, rows))


class AppendCsv:
    """A CSV file that grows by one row per call of :meth:`append` (constant cost per row).

    Created (atomically, with the rows so far) by the constructor; each row is one ``write`` of
    one complete line, flushed at once, so the file always holds the header and whole rows (the
    same bytes as :func:`write_csv` of all rows)."""

    def __init__(self, path: Path, header: list[str], rows: list[list] = ()):
        self.path = Path(path)
        self.header = list(header)
        write_csv(self.path, self.header, list(rows))
        self._f = open(self.path, "a", encoding="utf-8", newline="")

    def append(self, row: list) -> None:
        self._f.write(csv_line(row))
        self._f.flush()

    def close(self) -> None:
        if not self._f.closed:
            self._f.close()
