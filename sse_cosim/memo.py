"""A bounded memo of results computed from immutable inputs (geometries, zonotopes), kept by
those inputs' identities: a step asks for the same union, erosion or projection of the same
objects several times."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

T = TypeVar("T")


class IdentityMemo(Generic[T]):
    """The ``size`` most recently used results, each under a hashable key and the objects it
    was computed from.

    A hit needs the very same objects (``is``), not equal ones: a key may hold ``id`` values,
    and the memo keeps the objects themselves, so no id can be reused by another object while
    its entry is kept.
    """

    def __init__(self, size: int) -> None:
        self.size = size
        self._kept: OrderedDict[Hashable, tuple[tuple[object, ...], T]] = OrderedDict()

    def get(self, key: Hashable, inputs: tuple[object, ...], compute: Callable[[], T]) -> T:
        """The result kept for ``key`` if it was computed from ``inputs``, else ``compute()``
        (then kept)."""
        kept = self._kept.get(key)
        if kept is not None and len(kept[0]) == len(inputs) \
                and all(a is b for a, b in zip(kept[0], inputs, strict=True)):
            self._kept.move_to_end(key)
            return kept[1]
        value = compute()
        self._kept[key] = (inputs, value)
        self._kept.move_to_end(key)
        if len(self._kept) > self.size:
            self._kept.popitem(last=False)
        return value
