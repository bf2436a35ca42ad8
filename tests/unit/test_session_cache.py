"""The test session keeps out of the user's vibrogear cache (tests/conftest.py): unless the
caller names one, VIBROGEAR_CACHE_DIR is a temporary folder made for the session (shared by
the xdist workers, removed at the end)."""
import os
from pathlib import Path


def test_the_session_does_not_use_the_users_cache():
    d = os.environ.get("VIBROGEAR_CACHE_DIR")
    assert d, "the session runs with a cache folder of its own"
    assert Path(d).resolve() != (Path.home() / ".cache" / "vibrogear").resolve()
