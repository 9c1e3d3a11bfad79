"""Helpers of the typed facades (``twistslam.geometry``, ``.features``, ``.optim``) over the
bound C++ modules: each facade function is a typed Python wrapper whose docstring is the
binding's numpy-style docstring, so ``help()`` and type checkers both see one description."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


def doc_from(bound: Any) -> Callable[[F], F]:
    """Decorator: gives the wrapper the docstring of the bound function ``bound`` without the
    signature line pybind11 puts first (the wrapper's own annotations replace it)."""

    def wrap(function: F) -> F:
        text = bound.__doc__ or ""
        first, _, rest = text.partition("\n")
        if first.startswith(f"{bound.__name__}("):
            text = rest.lstrip("\n")
        function.__doc__ = text
        return function

    return wrap
