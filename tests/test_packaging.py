"""The wheel ships every package and every model file (a non-editable install must work)."""

import fnmatch
from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")  # Python 3.11+
ROOT = Path(__file__).resolve().parents[1]
SETUPTOOLS = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]


def test_every_python_package_is_listed():
    found = {
        ".".join(init.parent.relative_to(ROOT).parts)
        for top in ("aibo_sim", "openr_bridge")
        for init in (ROOT / top).rglob("__init__.py")
    }
    assert found <= set(SETUPTOOLS["packages"])


def test_every_model_file_is_package_data():
    patterns = SETUPTOOLS["package-data"]["aibo_sim.models"]
    models = ROOT / SETUPTOOLS["package-dir"]["aibo_sim.models"]
    for path in models.rglob("*"):
        if path.is_file():
            name = path.relative_to(models).as_posix()
            assert any(fnmatch.fnmatch(name, p) for p in patterns), f"models/{name} would be left out of the wheel"
