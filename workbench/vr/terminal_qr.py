"""The server's URL as a QR code in the terminal, for a headset's browser to scan."""

from __future__ import annotations

import io

__all__ = ["qr_text", "qr_matrix"]


def qr_matrix(url: str) -> list[list[bool]]:
    """The QR code of ``url`` as rows of modules (``True`` = dark), with a one-module quiet zone."""
    import qrcode

    code = qrcode.QRCode(border=1, error_correction=qrcode.constants.ERROR_CORRECT_M)
    code.add_data(url)
    code.make(fit=True)
    return [list(row) for row in code.get_matrix()]


def qr_text(url: str, *, unicode: bool = True) -> str:
    """The QR code of ``url`` for a terminal: half blocks (two modules per character) where the
    terminal shows Unicode, else ``##`` per dark module."""
    if not unicode:
        return "\n".join("".join("##" if dark else "  " for dark in row) for row in qr_matrix(url))
    import qrcode

    code = qrcode.QRCode(border=1, error_correction=qrcode.constants.ERROR_CORRECT_M)
    code.add_data(url)
    code.make(fit=True)
    text = io.StringIO()
    code.print_ascii(out=text, invert=True)
    return text.getvalue().rstrip("\n")
