"""mkbin for the host OPEN-R SDK: an object's ``.o`` and ``.a`` files into a loadable object.

Sony's mkbin links a relocatable MIPS image for Aperios; here the object is a shared library
that the runtime (``openr-host``) loads. Options as Sony's: ``-o OUT`` (default ``a.bin``),
``-p OPENRSDK_ROOT`` (default: the SDK this script belongs to), one ``.ocf`` file (or ``-m
FILE``; default OUT's name with ``.ocf`` for ``.bin``; Aperios loader hints, checked as Sony's
gensnap reads them, ``object`` then 7 or 14 words, and otherwise ignored), ``-v``,
``--nodefaultlib``, ``--nocrt``, ``--vm``, ``--novm`` (accepted, no effect); every other argument
(objects, archives, ``-L``, ``-l``, and ld's own options such as ``--wrap=exit``, which Sony's
mkbin hands to ld) goes to the linker, after which come ``-lObjectComm -lOPENR``
from the SDK. Symbols bind inside the object first (``-Bsymbolic``: two objects may define the
same names, as separate Aperios objects may), and an undefined one is an error at link time,
not when the robot loads the object.
"""

import subprocess
import sys
from pathlib import Path

NO_EFFECT = ("-v", "--nodefaultlib", "--nocrt", "--vm", "--novm")  # Sony's options, accepted
USAGE = "usage: mkbin [-p OPENRSDK_ROOT] -o OUTPUT.bin OBJECT.o ... [OBJECT.ocf] [-L DIR] [-l LIB]"


def parse(argv: list[str]) -> tuple[str, Path | None, Path | None, list[str]]:
    """(output, SDK root or None, .ocf or None, linker arguments); ValueError on bad usage."""
    output, root, ocf, rest = "a.bin", None, None, []
    arguments = list(argv)
    while arguments:
        argument = arguments.pop(0)
        for flag in ("-o", "-p", "-m"):
            if argument.startswith(flag) and argument != "--":
                value = argument[len(flag) :] or (arguments.pop(0) if arguments else None)
                if value is None:
                    raise ValueError(f"{flag} needs a value")
                if flag == "-o":
                    output = value
                elif flag == "-p":
                    root = Path(value)
                elif ocf is not None:
                    raise ValueError(".ocf given more than once")
                else:
                    ocf = Path(value)
                break
        else:
            if argument.endswith(".ocf"):
                if ocf is not None:
                    raise ValueError(".ocf given more than once")
                ocf = Path(argument)
            elif argument in NO_EFFECT:
                continue
            elif argument.startswith("--"):
                rest.append("-Wl," + argument)  # ld's own option (--wrap=exit): Sony's mkbin hands it to ld
            else:
                rest.append(argument)
    return output, root, ocf, rest


def check_ocf(ocf: Path) -> None:
    """ValueError naming the file unless, without its ``#`` comments, it is ``object`` then 7
    words (NAME stack heap sched cache tlb mode) or 14, as Sony's gensnap requires."""
    try:
        text = ocf.read_text(errors="replace")
    except OSError as error:
        raise ValueError(f"{ocf}: {error.strerror or error}") from None
    words = " ".join(line.split("#", 1)[0] for line in text.splitlines()).split()
    if words[:1] != ["object"] or len(words) - 1 not in (7, 14):
        got = " ".join(words) if len(words) <= 16 else " ".join(words[:16]) + " ..."
        raise ValueError(
            f"{ocf}: ocf format error: expected 'object NAME stack heap sched cache tlb mode' (or 14 words "
            f"after 'object'), got {got!r}"
        )


def main(argv: list[str], cxx: str) -> int:
    try:
        output, root, ocf, rest = parse(argv)
        check_ocf(ocf or Path(output.removesuffix(".bin") + ".ocf"))
    except ValueError as error:
        print(f"mkbin: {error}\n{USAGE}", file=sys.stderr)
        return 2
    library = root / "OPEN_R" / "lib" if root is not None else Path(sys.argv[0]).resolve().parents[1] / "lib"
    command = [
        cxx,
        "-shared",
        "-o",
        output,
        *rest,
        "-L",
        str(library),
        "-lObjectComm",
        "-lOPENR",
        "-Wl,-Bsymbolic",
        "-Wl,--no-undefined",
    ]
    return subprocess.run(command).returncode
