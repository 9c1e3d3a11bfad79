"""The lazy import of ``rerun``: the live view is an optional extra."""

from __future__ import annotations

import importlib
from types import ModuleType

INSTALL_HINT = "pip install 'twistslam[viz]' (or pip install rerun-sdk)"


def import_rerun() -> ModuleType:
    """Import the rerun SDK, or explain how to install it.

    Returns
    -------
    ModuleType
        The ``rerun`` module.

    Raises
    ------
    ImportError
        When ``rerun-sdk`` is not installed, naming the command that installs it.
    """
    try:
        return importlib.import_module("rerun")
    except ImportError as exc:
        raise ImportError(f"the rerun view needs the rerun SDK, which is not installed: "
                          f"{INSTALL_HINT}") from exc
