"""Frame dumps: every head-camera frame of a headless run, in the formats vision code reads.

Usage::

    aibo-sim dump (CONTROLLER | --env ENV_ID [--policy random|scripted|zero]) --out DIR
    aibo-sim dump [CONTROLLER] (--robots FILE | --robot TEAM:NUMBER[:X,Y,YAW_DEG][:CONTROLLER] ...) --out DIR
                  [--duration S | --steps N] [--backend sim|openr] [--mtn-mode openr|webots]
                  [--memory-stick DIR] [--scene FILE] [--pose X Y YAW_DEG] [--ball X Y]
                  [--ball-type robocup|pink] [--seed N]
                  [--camera-profile ers7|ideal] [--camera-wb W] [--camera-gain G] [--camera-shutter S]
                  [--formats rgb,yuv444,yuv420,annex,openr,bands,luma,depth,seg,robots,mp4,coco | all]
                  [--camera-full] [--resume] [--workers N] [--engine local|ray] [--ray-address ADDR]

A controller dump holds camera frames 0 .. 30 S - 1 (``--steps N``: frames 0 .. N - 1); an
environment dump runs N ``env.step`` calls (``--duration S``: 30 S) and holds the frame of
every observation, each episode's reset frame included. Default formats: rgb, yuv420,
openr, mp4 (a viewable picture, a video tool's YUV, the robot's bytes, a video).

Layout of ``DIR`` (frame files are named by the frame's index in the dump, which for a
controller is the camera frame index, k / 30 s)::

    meta.json            run parameters, the camera (profile, settings, OpenCV intrinsics and
                         distortion), every file's path and layout
    frames.jsonl         one line per complete frame (see ``frame_metadata``)
    .dump.lock           the writer's lock: pid, command and start time of the dump writing now
    controller_files/    a controller dump's working folder: the files the controller writes
                         (``run --out`` puts them in its folder); each shard has its own
    rgb/000123.png       8-bit RGB
    yuv444/000123.yuv    I444 planar: Y, then U (Cb), then V (Cr), each w x h
    yuv420/000123.yuv    I420 planar: Y (w x h), U, V (w/2 x h/2): ffmpeg -pix_fmt yuv420p
    annex/000123.yuv     the report's Annex I: bytes Y, U, V per pixel, row-major
    openr/000123.ofbk    the OFbkImageVectorData message, as bytes(message)
    bands/000123_H.raw   each layer's data as Sony's sample writes it: 6 w h bytes for
                         H, M, L (rows of Y, Cr, Cb, Y_LH, Y_HL, Y_HH), w h for C
    luma/000123.png      the 416x320 luma reconstructed from layer H (reconstruct_luma)
    depth/000123.npy     float32 metres along the optical axis, through the same lens
    seg/000123.png       uint8 class ids, names in meta.json (field.SEGMENTATION_CLASSES), same lens
    robots/000123.png    uint8 robot instance ids, same lens: 0 no robot, k the world's robot k (a
                         match's meta.json "robots" names each; a lone robot's own paws are 1)
    video.mp4            30 fps, codec mp4v (MPEG-4 part 2: OpenCV's wheels lack H.264), its index
                         (moov) ahead of the frames, as ffmpeg's +faststart leaves it
    coco.json            COCO detection annotations of the rgb files (needs rgb): a box and a
                         mask per visible ball, goal, beacon and robot, with its visibility (``coco.py``)

Colour: the yuv444 and yuv420 files are BT.601 limited range (Y 16-235, Cb/Cr 16-240), what
ffmpeg, ffplay and OpenCV's ``COLOR_YUV2RGB_I420`` assume for raw yuv420p; 4:2:0 chroma is
the mean of each 2x2 block. The Annex I file uses the report's own formulas (Y = 0.299 R +
0.587 G + 0.114 B, U = 0.492 (B - Y) + 128, V = 0.5 (R - Y) + 128, truncated as C casts).
The OPEN-R message and bands hold Sony's YCrCb (Cr before Cb), as ``encode_frame`` makes it.
All are the head camera's frame (``aibo_sim.camera``: the picture exposed at the frame's tick,
the same frames ``aibo-sim run`` shows) and its one OPEN-R message; ``--backend`` only
chooses what the controller (or an environment, as ``camera="openr"``) sees.

Writes are atomic: each file is written under a ``.tmp.`` name and renamed, and a frame's
line goes into frames.jsonl after all its files. A frame is complete when its line is
there; readers see only complete frames. ``--resume`` re-runs the same simulation from the
start (it is deterministic for a seed: a resumed dump is byte-identical to an uninterrupted
one, whatever the formats), drops a partial last line, writes the frames that are not
complete, rewrites those listed whose files are missing or, in a fixed-size format (every
one but the PNGs), of the wrong size, and rebuilds video.mp4 from every frame. The
controller runs again from the start in controller_files/, rewriting its files there.
coco.json is written at the end from frames.jsonl's records (each frame's ``"objects"``),
so a resumed dump's is the same too. It refuses a dump made with other parameters or from
a controller file whose content changed since (meta.json records its SHA-256).

One writer per folder: a dump holds an ``flock`` on ``DIR/.dump.lock`` (which names its
pid, command and start time) while it writes; a second dump or ``--resume`` into the folder
stops with exit status 2 and that holder's description, changing nothing. ``--out`` must be
a new or empty folder, or a dump (with ``--resume``): any other folder is refused the same
way. Only the dump's own temporary files (``.tmp.`` + its file names, in its folders) are
ever removed; no file is written or read through a symbolic link (``files.SymlinkRefused``).
A corrupt meta.json or frames.jsonl is an error that names the file and line (``load_dump``
too).

``--workers N`` (at most what memory holds, about 200 MB a worker: more is refused, saying
how many fit) splits the frames into N shards run in parallel processes, written to
``DIR/shard_k/`` (each a dump of the layout above, with its own video.mp4); shard k uses
seed ``seed + k`` and, in a controller dump without ``--ball`` whose scene has a ball it can
place, a ball position drawn from that seed. ``load_dump`` reads a sharded dump as
the shards' frames one after the other. The workers end with the dump: killed with it
(SIGKILL too: ``PR_SET_PDEATHSIG`` on Linux, and everywhere a watch on the parent), stopped when
it fails. A SIGTERM stops a dump cleanly (workers stopped, temporary files removed, exit
status 143); Ctrl-C the same way, with exit status 130. Either can continue with ``--resume``.
A sharded dump's coco.json lists every shard's frames (file names ``shard_k/rgb/...``).

``--engine ray`` runs the shards as Ray tasks (``pip install 'aibo-sim[ray]'``): on the
cluster at ``--ray-address`` (``ray start --head`` on one machine, ``ray start --address``
on the others; each with aibo-sim installed and ``--out`` at the same path, a shared file
system), or on a local Ray started for the dump. The files are the local engine's, byte for
byte; locking, ``--resume`` and the errors are the same. A task whose worker is lost runs
again (resuming its shard), up to 3 retries.

A match (``--robots FILE`` or ``--robot ...``, as ``aibo-sim run`` takes them; CONTROLLER runs
the robots whose entry names none) is dumped one robot a shard: ``DIR/robot1/``, ``DIR/robot2/``,
... (in the robots' order), each the layout above for that robot's camera, its meta.json
recording its spec (``"parameters"."robot"``) and the match (``"robots"``: each robot's instance
id, team, number and name, ``"observer"`` the robot itself); ``load_dump`` reads robot 1's frames,
then robot 2's, ...; ``DIR/coco.json`` lists them all, the robots in their teams' categories
(``robot_red``, ``robot_blue``), no robot detecting itself. The controllers share
``DIR/controller_files/``. ``--resume`` runs the match again and writes what is missing;
``--workers``, ``--env`` and the one robot's options (``--pose``, ``--backend``, ``--mtn-mode``,
``--memory-stick``) are refused (``match.py``).

On a terminal a dump shows its progress (frames, simulated time, real-time factor, time
left); elsewhere it is quiet.

Modules: ``formats`` (what each format writes), ``writing`` (atomic files, the lock, resume),
``running`` (one run into a writer; ``dump``), ``shards`` (worker processes and Ray tasks),
``coco`` (detection labels), ``reading`` (``load_dump``), ``match`` (a match's dump), ``command``
(the CLI).
"""

from .command import add_dump_parser
from .formats import (
    DEFAULT_FORMATS,
    DUMP_FORMAT,
    FORMATS,
    DumpError,
    annex_yuv,
    ball_in_image,
    file_layouts,
    frame_metadata,
    geom_classes,
    rgb_to_yuv_bt601,
    yuv420_bytes,
    yuv444_bytes,
)
from .reading import Dump, DumpFrame, load_dump
from .running import POLICIES, dump
from .writing import DumpSummary, DumpWriter

__all__ = [
    "DEFAULT_FORMATS",
    "DUMP_FORMAT",
    "FORMATS",
    "POLICIES",
    "Dump",
    "DumpError",
    "DumpFrame",
    "DumpSummary",
    "DumpWriter",
    "add_dump_parser",
    "annex_yuv",
    "ball_in_image",
    "dump",
    "file_layouts",
    "frame_metadata",
    "geom_classes",
    "load_dump",
    "rgb_to_yuv_bt601",
    "yuv420_bytes",
    "yuv444_bytes",
]
