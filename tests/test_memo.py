"""The identity memo behind the per-step caches (unions, erosions, position sets, regions)."""

from __future__ import annotations

from sse_cosim.memo import IdentityMemo


def test_a_hit_needs_the_very_same_inputs_and_the_oldest_entry_goes_first():
    memo: IdentityMemo[int] = IdentityMemo(2)
    calls: list[str] = []

    def compute(name: str, value: int):
        return lambda: calls.append(name) or value

    a, b, c = [1.0], [2.0], [3.0]
    assert memo.get("a", (a,), compute("a", 1)) == 1
    assert memo.get("a", (a,), compute("a again", 9)) == 1  # same object: kept
    assert memo.get("a", ([1.0],), compute("equal copy", 2)) == 2  # equal, not the same
    assert memo.get("b", (b,), compute("b", 3)) == 3
    assert memo.get("a", ([1.0],), compute("copy again", 4)) == 4  # the copy was not kept
    memo.get("c", (c,), compute("c", 5))  # three keys in a memo of two: "b" goes
    assert memo.get("b", (b,), compute("b again", 6)) == 6
    assert calls == ["a", "equal copy", "b", "copy again", "c", "b again"]
