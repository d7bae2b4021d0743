"""aibo-sim: a MuJoCo simulator of the Sony Aibo ERS-7 with OPEN-R's camera data path."""

from ._gl import choose_gl_backend, import_mujoco

choose_gl_backend()  # before anything imports mujoco
import_mujoco()

from .envs import register_envs  # noqa: E402,F401  (registers the gymnasium environments)

__version__ = "0.1.0"
