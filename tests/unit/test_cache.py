"""The on-disk cache heals: entries are verified against the manifest written last; a
corrupted, truncated, tampered or half-written entry is rebuilt with a warning; ``cache
clear`` deletes only the cache's own entries (issue 14)."""
from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pytest

from vibrogear import cache
from vibrogear.cli import main

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def cdir(tmp_path, monkeypatch):
    d = tmp_path / "cache"
    monkeypatch.setenv("VIBROGEAR_CACHE_DIR", str(d))
    return d


def _entry(key="thing-0123456789abcdef0123", payload=b"payload" * 100):
    tmp = cache.new_workspace(key)
    (tmp / "data.bin").write_bytes(payload)
    (tmp / "sub").mkdir()
    (tmp / "sub" / "meta.json").write_text('{"a": 1}')
    return key, cache.publish_entry(tmp, key)


def test_published_entry_opens_and_manifest_lists_every_file(cdir):
    key, folder = _entry()
    assert cache.open_entry(key) == folder
    manifest = json.loads((folder / cache.MANIFEST).read_text())
    assert manifest["key"] == key and set(manifest["files"]) == {"data.bin", "sub/meta.json"}
    assert [p.name for p in cdir.iterdir()] == [key]            # no workspace left behind


@pytest.mark.parametrize("damage, why", [
    (lambda f: f.joinpath("data.bin").write_bytes(b"payload"), "checksum mismatch"),   # truncated
    (lambda f: f.joinpath("data.bin").write_bytes(b"PAYLOAD" * 100), "checksum mismatch"),  # tampered
    (lambda f: f.joinpath("sub", "meta.json").unlink(), "files missing"),
    (lambda f: f.joinpath(cache.MANIFEST).write_text("{garbage"), "unreadable manifest"),
    (lambda f: f.joinpath(cache.MANIFEST).unlink(), "no manifest"),            # half-written
    (lambda f: f.joinpath("extra.txt").write_text("x"), "unexpected"),
])
def test_damaged_entry_is_removed_with_a_warning(cdir, caplog, damage, why):
    key, folder = _entry()
    damage(folder)
    with caplog.at_level(logging.WARNING, logger="vibrogear.cache"):
        assert cache.open_entry(key) is None
    assert not folder.exists()
    assert any(why in r.getMessage() and key in r.getMessage() for r in caplog.records)
    key2, folder2 = _entry()                                  # rebuilt in its place
    assert cache.open_entry(key2) == folder2


def test_clear_deletes_only_its_own_entries(cdir):
    key, folder = _entry()
    stale = cdir / ".thing-0123456789abcdef0123.abc123"        # an unfinished workspace
    stale.mkdir()
    old = cdir / "housing-modes-00000000000000000000"          # an entry of an older version
    old.mkdir()
    (old / "meta.json").write_text("{}")
    mine = {folder, stale, old}
    strangers = [cdir / "notes.txt", cdir / "photos", cdir / "x-0123456789abcdef0123"]
    strangers[0].write_text("keep me")
    strangers[1].mkdir()
    strangers[2].mkdir()                                        # key-like name, not ours
    (strangers[2] / "data").write_text("keep")
    assert cache.cache_info()["entries"] == 3
    assert cache.clear_cache() == (3, 3)
    assert not any(p.exists() for p in mine)
    assert all(p.exists() for p in strangers)
    assert main(["cache", "clear"]) == 0


def test_cache_folder_that_is_a_file_is_an_input_error(tmp_path, monkeypatch, capsys):
    f = tmp_path / "cachefile"
    f.write_text("x")
    monkeypatch.setenv("VIBROGEAR_CACHE_DIR", str(f))
    for action in ("clear", "info"):
        assert main(["cache", action]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err
    with pytest.raises(cache.ConfigError):
        cache.entry_dir("thing-0123456789abcdef0123")


def test_cache_key_depends_on_content_and_stage_prefix_only():
    a = cache.cache_key("housing-modes", {"x": 1.0})
    assert a == cache.cache_key("housing-modes", {"x": 1.0})
    assert a != cache.cache_key("housing-modes", {"x": 1.0 + 1e-12})
    assert cache.KEY_RE.fullmatch(a)
    assert cache.cache_key("housing-matrices", {"x": 1.0}).split("-")[-1] == a.split("-")[-1]


def test_housing_modes_entry_heals(cdir, caplog):
    """A truncated and then a tampered-but-valid modes.npz of a real housing entry: each is
    detected, rebuilt with a warning, and the rebuilt frequencies equal the first solve's
    (the FE solve is deterministic); a verified entry is loaded without FE work."""
    pytest.importorskip("dolfinx")
    from vibrogear.config import load_scene
    from vibrogear.config.base import as_data, build
    from vibrogear.config.model.housing import HousingConfig
    from vibrogear.models.housing.run import housing_cache_key, housing_modes

    data = as_data(load_scene(ROOT / "configs" / "housing_small.toml").housing)
    data["modes"].update(count=6, shapes=0)
    cfg = build(HousingConfig, data, "housing")
    first = housing_modes(cfg)
    key = housing_cache_key(cfg, "modes")
    folder = cdir / key
    assert not first.cached and cache.open_entry(key) == folder
    hit = housing_modes(cfg)
    assert hit.cached and np.array_equal(hit.freqs_hz, first.freqs_hz)

    npz = folder / "modes.npz"
    npz.write_bytes(npz.read_bytes()[:100])                     # truncated
    with caplog.at_level(logging.WARNING, logger="vibrogear.cache"):
        again = housing_modes(cfg)
    assert not again.cached and np.array_equal(again.freqs_hz, first.freqs_hz)
    assert any("checksum mismatch in modes.npz" in r.getMessage() for r in caplog.records)

    with np.load(npz) as z:                                     # tampered, still a valid npz
        arrays = {k: z[k] for k in z.files}
    arrays["freqs_hz"] = arrays["freqs_hz"] * 2
    np.savez(npz, **arrays)
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="vibrogear.cache"):
        healed = housing_modes(cfg)
    assert not healed.cached and np.array_equal(healed.freqs_hz, first.freqs_hz)
    assert any("checksum mismatch" in r.getMessage() for r in caplog.records)
    assert housing_modes(cfg).cached
