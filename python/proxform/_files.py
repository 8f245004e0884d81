"""Reading the files a user names: regular files only, of bounded size, as UTF-8 text."""

from __future__ import annotations

import os
import stat

from ._proxform import ScenarioError

#: Largest scenario or comparison file read (bytes), as on the command line.
MAX_INPUT_BYTES = 16 << 20


def read_text(path: str, what: str) -> str:
    """The text of the file at ``path``; a FIFO, a device or a folder is refused before
    anything is read from it. Errors are :class:`ScenarioError` naming the file."""

    def fail(message: str) -> ScenarioError:
        e = ScenarioError(f"{path}: {message}")
        e.key, e.line, e.source = None, None, path
        return e

    try:
        st = os.stat(path)
    except OSError as e:
        raise fail(f"cannot read {what}: {e.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        raise fail(f"{what} is not a regular file")
    if st.st_size > MAX_INPUT_BYTES:
        raise fail(
            f"{what} is {st.st_size} bytes, more than the {MAX_INPUT_BYTES} bytes ({MAX_INPUT_BYTES >> 20} MiB) a {what} may have"
        )
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_INPUT_BYTES + 1)
    except OSError as e:
        raise fail(f"cannot read {what}: {e.strerror}") from None
    if len(data) > MAX_INPUT_BYTES:
        raise fail(f"{what} grew past {MAX_INPUT_BYTES >> 20} MiB while being read")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise fail(f"cannot read {what} as UTF-8 text (byte {e.start})") from None
