"""Real OPEN-R programs in the simulator: the host OPEN-R SDK (``sdk.py``, ``mkbin.py``) that Sony's
Makefiles build against, and the runner of a memory stick's objects on the simulated ERS-7
(``host.py``). The objects' headers and runtime are ``openr_bridge/sdk``; the robot side of the
protocol is ``openr_bridge.host_protocol``."""
