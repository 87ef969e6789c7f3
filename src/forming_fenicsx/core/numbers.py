"""Numbers read from text on the command line: whether a word is one (a PETSc option's value, a
--vary value), and a relative value written as a fraction or in percent (--accuracy)."""
from __future__ import annotations


def is_number(text: str) -> bool:
    """Whether ``text`` reads as a number, as float() reads it (3, -1e-3, inf)."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def fraction(text: str) -> float:
    """A relative value written "1%" or "0.01", as 0.01; ValueError when it is neither."""
    text = text.strip()
    percent = text.endswith("%")
    return float(text.removesuffix("%")) / (100 if percent else 1)
