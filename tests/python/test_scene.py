"""Scene files from Python (README.md "Scene files"): config=FILE is the command line's --config,
the keyword arguments override it, and a bad file raises ValueError with the one-line message."""
import os

import pytest

import netdem
from conftest import assert_same_run, run_cli

SMALL = ["--width", "20", "--increments", "40", "--quiet"]


def test_netsolve_config_overridden_equals_cli(tmp):
    code, _ = run_cli("netsolve", ["compact"] + SMALL + ["--friction", "0.3", "--out", f"{tmp}/a"])
    assert code in (0, 3)
    r = netdem.netsolve.compact(config=f"{tmp}/a/scene.toml", friction=0.1, out=f"{tmp}/py")
    code, _ = run_cli("netsolve", ["compact"] + SMALL + ["--friction", "0.1", "--out", f"{tmp}/cli"])
    assert r.exit_code == code
    with open(f"{tmp}/py/scene.toml") as f:
        scene = f.read()
    assert 'friction = "0.1"\n' in scene and 'width = "20"\n' in scene
    assert_same_run(f"{tmp}/cli", r)  # scene.toml too, byte for byte


def test_demsolve_config_equals_cli(tmp):
    with open(f"{tmp}/scene.toml", "w") as f:
        f.write('[compact]\nwidth = 8\nincrements = 3\nto-density = 0.8\nquiet = true\n')
    r = netdem.demsolve.compact(config=f"{tmp}/scene.toml", out=f"{tmp}/py")
    code, _ = run_cli("demsolve", ["compact", "--width", "8", "--increments", "3", "--to-density", "0.8", "--quiet",
                                   "--out", f"{tmp}/cli"])
    assert r.exit_code == code == 0 and len(r.history["D"]) == 4
    assert_same_run(f"{tmp}/cli", r)  # scene.toml too: the file's values are written as the command line's


@pytest.mark.parametrize("text,word", [("[compact]\nwidht = 20\n", "widht"), ("width = 20\n", "outside a section"),
                                       (None, "missing.toml")])
def test_bad_scene_file_raises(tmp, text, word):
    path = f"{tmp}/missing.toml"
    if text is not None:
        path = f"{tmp}/bad.toml"
        with open(path, "w") as f:
            f.write(text)
    code, err = run_cli("netsolve", ["compact", "--config", path, "--out", f"{tmp}/cli"])
    with pytest.raises(ValueError) as e:
        netdem.netsolve.compact(config=path, out=f"{tmp}/py")
    assert code == 2 and word in str(e.value) and str(e.value) == err.strip()
    assert not os.path.exists(f"{tmp}/py") and not os.path.exists(f"{tmp}/cli")
