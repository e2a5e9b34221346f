"""Every OpenSCENARIO test shares one netconvert cache per session (a road converted once is
reused by every test that runs it), outside the user's own cache."""

import pytest


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))
