"""Errors the CLI reports as one clear line with exit code 2."""

from __future__ import annotations


class UsageError(Exception):
    """Bad input from the user: unknown behaviour, bad option, unusable checkpoint.

    The message names what was wrong and what is valid.
    """


class RunStopped(UsageError):
    """Training stopped on a fault it names (a non-finite reward, a dead env worker...); the
    message says where the checkpoint of the last good state was written."""
