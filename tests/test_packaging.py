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


def _import_aibo_sim(**env: str):
    import os
    import subprocess
    import sys

    environment = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "LP_NUM_THREADS")} | env
    code = "import os, aibo_sim; print(os.environ['MUJOCO_GL'], os.environ['LP_NUM_THREADS'])"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=environment, cwd=ROOT)


@pytest.mark.slow
def test_import_chooses_a_headless_backend_and_keeps_the_users_settings():
    chosen = _import_aibo_sim()
    assert chosen.returncode == 0, chosen.stderr
    assert chosen.stdout.split() in (["egl", "0"], ["osmesa", "0"])
    kept = _import_aibo_sim(MUJOCO_GL=chosen.stdout.split()[0], LP_NUM_THREADS="3")
    assert kept.stdout.split() == [chosen.stdout.split()[0], "3"]


def test_unusable_mujoco_gl_fails_at_import_with_a_clear_message():
    result = _import_aibo_sim(MUJOCO_GL="nonsense")
    assert result.returncode != 0
    last = result.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError: MuJoCo cannot load the OpenGL backend MUJOCO_GL='nonsense'")
    assert "unset MUJOCO_GL" in last


def test_unusable_mujoco_gl_is_one_line_and_exit_2_for_the_command_line():
    import os
    import subprocess
    import sys

    environment = {**os.environ, "MUJOCO_GL": "nonsense"}
    for command in (["-m", "aibo_sim.cli"], ["-c", "import sys; sys.argv[0] = 'aibo-sim'; import aibo_sim.cli"]):
        result = subprocess.run(
            [sys.executable, *command, "mtn", "info", "x.mtn"],
            capture_output=True,
            text=True,
            env=environment,
            cwd=ROOT,
        )
        assert result.returncode == 2
        assert result.stderr.startswith("aibo-sim: error: MuJoCo cannot load the OpenGL backend MUJOCO_GL='nonsense'")
        assert len(result.stderr.splitlines()) == 1
