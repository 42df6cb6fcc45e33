"""The exceptions of mint_mesh: one base class, one subclass per kind of
failure, each carrying the command line's one-line message."""

from __future__ import annotations


class MintError(Exception):
    """Base class of every error mint reports (the CLI's one-line message)."""


class UsageError(MintError, ValueError):
    """An option mint does not know, or a value it cannot parse."""


class InputError(MintError):
    """The input is malformed or unusable: a damaged file, a NaN vertex,
    an index out of range, an empty mesh."""


class MintIOError(MintError, OSError):
    """Reading or writing a file failed: missing, unreadable, a full disk."""


class BudgetError(MintError, MemoryError):
    """The memory budget (``mem``) is too small for the job; the message
    says how much would do."""


class CancelledError(MintError):
    """The run was stopped by its progress callback (returning ``False``);
    nothing was written."""


class MintWarning(UserWarning):
    """A surprising result (an empty output, colours dropped, a relaxed
    target): the command line's warning lines."""


_KINDS = {
    "usage": UsageError,
    "input": InputError,
    "io": MintIOError,
    "budget": BudgetError,
    "cancelled": CancelledError,
}


def error_of(kind: str, message: str) -> MintError:
    """The exception for a failure of ``kind`` with the CLI's ``message``."""
    return _KINDS.get(kind, MintError)(message)
