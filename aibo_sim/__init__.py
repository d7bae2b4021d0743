"""aibo-sim: a MuJoCo simulator of the Sony Aibo ERS-7 with OPEN-R's camera data path."""

__version__ = "0.1.0"
