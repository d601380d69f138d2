"""Test-wide settings: hypothesis draws the same examples on every run (deterministic seeds
everywhere), so a failure is reproduced by running the test again."""

from hypothesis import settings

settings.register_profile("deterministic", derandomize=True, print_blob=True)
settings.load_profile("deterministic")
