"""C and C++ controllers: the Webots-era headers, compiled with the system compiler, bound to
the running simulation through the Python API."""

import fnmatch
import json
import os
import re
import shutil
import signal
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from aibo_sim import cbind, controller
from aibo_sim.cbind import headers, protocol, serve
from aibo_sim.cli import main
from aibo_sim.config import CameraConfig
from aibo_sim.mtn import read_mtn
from aibo_sim.runner import ControllerFailed, run_controller
from aibo_sim.sim import models_dir
from openr_bridge import ers7_camera

ROOT = Path(__file__).resolve().parents[1]
TOUR = ROOT / "tests" / "controllers" / "api_tour"
ECHO = ROOT / "tests" / "controllers" / "api_echo"
ANNEX_C, ANNEX_PY = ROOT / "controllers" / "annex_capture_c", ROOT / "controllers" / "annex_capture.py"
SONY_WWFWD = ROOT.parent / "shared" / "data" / "mtn" / "WWFWD.MTN"  # test data, not shipped

pytestmark = pytest.mark.skipif(not (shutil.which("cc") and shutil.which("c++")), reason="needs cc and c++")


@pytest.fixture(autouse=True)
def own_cache(tmp_path_factory, monkeypatch):
    """Each test session compiles into its own cache (the user's is left alone)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))


def c_file(tmp_path, name: str, body: str) -> Path:
    path = tmp_path / name
    path.write_text(
        "#include <stdio.h>\n#include <stdlib.h>\n#include <device/robot.h>\n#include <device/servo.h>\n" + body
    )
    return path


def test_every_api_function_gives_in_c_what_it_gives_in_python(tmp_path):
    """The tour calls every function (reset, run, die; enable, disable; a failed and a
    case-insensitive mtn_new) and writes each result; the C and Python twins agree line for
    line, and their trajectories and camera frames are identical."""
    runs = {}
    for name, path in (("c", TOUR), ("python", TOUR / "api_tour.py")):
        runs[name] = run_controller(path, duration=0.5, out=tmp_path / name, camera=CameraConfig("ideal"))
    tour = (tmp_path / "c" / "tour.txt").read_text()
    assert tour == (tmp_path / "python" / "tour.txt").read_text()
    assert "missing 1 error File not found: no_such_motion.mtn" in tour and "walk a_walk#walk_fwd length 320" in tour
    assert tour.count("\nt ") == 8 and tour.endswith("die at 0.504\n")
    assert "\nsaved 0 0\n" in tour and "\nkeys 315 65601 65535\n" in tour  # Webots' codes
    third = tour.split("\nt ")[3]
    png = cv2.imread(str(tmp_path / "c" / "tour.png"))
    assert int(third.split(" sum ")[1].split()[0]) == int(png.astype(int).sum())  # the picture of the third step
    for name in ("tour.png", "tour.jpg"):
        assert (tmp_path / "c" / name).read_bytes() == (tmp_path / "python" / name).read_bytes(), name
    assert np.abs(cv2.imread(str(tmp_path / "c" / "tour.jpg")).astype(int) - png).mean() < 3  # quality 75
    assert runs["c"].robot_pose == runs["python"].robot_pose and runs["c"].camera_frames == 15
    for frame in sorted((tmp_path / "python" / "frames").iterdir()):
        assert (tmp_path / "c" / "frames" / frame.name).read_bytes() == frame.read_bytes(), frame.name


def _as_received(name: str, result) -> str:
    """A Python API result as api_echo.cc writes what its C call returned (``protocol.OPS`` types)."""
    kind = {name: results for name, _, results in protocol.OPS}[name]
    if name == "camera_get_fov":  # float in C
        return f"{float(np.float32(result)):.17g}"
    if name == "mtn_new":  # the C side sees NULL or not
        return str(int(result != 0))
    if kind == "ddd":  # const float * in C
        return " ".join(f"{float(np.float32(v)):.9g}" for v in result)
    return {"i": lambda: str(int(result)), "d": lambda: f"{result:.17g}", "s": lambda: str(result), "m": lambda: ""}[
        kind
    ]()


@pytest.mark.parametrize("backend", ["sim", "openr"])
def test_each_c_call_returns_what_the_python_api_returned_in_the_same_run(tmp_path, monkeypatch, backend):
    """api_echo.cc calls every function of ``protocol.OPS`` (and the pixel macros); what each
    call received, value for value and byte for byte, is what the Python API returned for the
    same call at the same simulated time (made then, or ahead with robot_step's answer)."""
    returned, called = {}, set()  # (time in ms, name, argument) -> result
    handlers = serve._handlers

    def recording(image):
        def record(name, function):
            def call(*args):
                now = controller.current_robot().time_ms
                result = function(*args)
                called.add(name)
                if {n: r for n, _, r in protocol.OPS}[name]:
                    on_motion = name.startswith("mtn_") and name not in ("mtn_new", "mtn_get_error")
                    kept = bytes(image[: result[0] * result[1] * 3]) if name == "camera_get_image" else result
                    returned[now, name, "mtn" if on_motion else str(args[0]) if args else "0"] = kept
                return result

            return call

        return {name: record(name, function) for name, function in handlers(image).items()}

    monkeypatch.setattr(serve, "_handlers", recording)
    assert run_controller(ECHO, backend=backend, duration=1, out=tmp_path).simulated_s == 0.224
    assert called == {name for name, _, _ in protocol.OPS}
    now, images, lines = 0, [], (tmp_path / "echo.txt").read_text().splitlines()
    for line in lines:
        name, argument, value = line.split(" ", 2)
        result = returned[now, name, argument]
        if name == "camera_get_image":
            images.append(np.frombuffer(result, np.uint8))
        else:
            assert value == _as_received(name, result), line
        if name == "robot_step":
            now += int(argument)
    assert len(lines) == 74 and len(images) == 4
    assert (tmp_path / "images.bin").read_bytes() == b"".join(i.tobytes() for i in images)
    assert np.array_equal(cv2.imread(str(tmp_path / "echo.png"))[:, :, ::-1].reshape(-1), images[-1])  # the last
    assert (tmp_path / "fprint.txt").read_text() == returned[0, "mtn_fprint", "mtn"]
    pixel = (
        controller.camera_image_get_red,
        controller.camera_image_get_green,
        controller.camera_image_get_blue,
        controller.camera_image_get_grey,
        controller.camera_image_get_gray,
    )
    assert (tmp_path / "pixels.txt").read_text() == "".join(
        " ".join(str(int(f(i, 208, 10, 20))) for f in pixel) + "\n" for i in images
    )
    assert "mtn_get_error 0 File not found: missing.mtn" in lines


MOTIONS = {"WALKFWD.MTN": models_dir() / "motions" / "WALKFWD.MTN", "Sony's WWFWD.MTN": SONY_WWFWD}


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["sim", "openr"])
@pytest.mark.parametrize("motion", MOTIONS)
def test_annex_i_in_cpp_writes_the_python_ports_image_raw_byte_for_byte(tmp_path, backend, motion):
    """Both as shipped, each finding the same motion file beside it under the name it asks for
    (the C++ Annex "wwfwd.mtn", the Python port "WALKFWD.MTN"), 15 plays at 16 ms steps."""
    if not MOTIONS[motion].is_file():
        pytest.skip(f"{MOTIONS[motion]} not present")
    (tmp_path / "annex_capture_c").mkdir()
    cpp = shutil.copy(ANNEX_C / "annex_capture_c.cpp", tmp_path / "annex_capture_c")
    python = shutil.copy(ANNEX_PY, tmp_path)
    shutil.copy(MOTIONS[motion], tmp_path / "annex_capture_c" / "WWFWD.MTN")
    shutil.copy(MOTIONS[motion], tmp_path / "WALKFWD.MTN")
    duration = 15 * (read_mtn(MOTIONS[motion]).length_ms + 32) / 1000 + 0.2  # 15 plays, then an image
    images = []
    for name, path in (("cpp", Path(cpp).parent), ("python", python)):
        out = tmp_path / f"out_{name}"
        assert main(["run", str(path), "--duration", f"{duration:.3f}", "--backend", backend, "--out", str(out)]) == 0
        images.append((out / "image.raw").read_bytes())
    assert len(images[0]) == 208 * 160 * 3 and images[0] == images[1]


def test_annex_i_in_cpp_without_its_motion_file_says_so(tmp_path):
    (tmp_path / "annex_capture_c").mkdir()
    shutil.copy(ANNEX_C / "annex_capture_c.cpp", tmp_path / "annex_capture_c")
    with pytest.raises(
        ControllerFailed, match=r"mtn_is_over: MTN is NULL: mtn_new failed \(File not found: wwfwd.mtn\)"
    ):
        run_controller(tmp_path / "annex_capture_c", duration=1)


def test_camera_save_image_writes_where_and_what_the_c_controller_names(tmp_path, capfd):
    """A relative name is from the C controller's working folder (it landed in the simulator's), and
    a name that is not UTF-8 keeps its bytes (U+FFFD replaced them)."""
    body = r"""#include <device/camera.h>
#include <sys/stat.h>
#include <unistd.h>
static DeviceTag camera;
static void init(void) {
    camera = robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1");
    camera_enable(camera, 32);
}
static int run(int ms) {
    if (ms == 0) return 64;
    mkdir("sub", 0777);
    chdir("sub");
    printf("saved %d %d\n", camera_save_image(camera, "here.png", 0), camera_save_image(camera, "caf\xe9.png", 0));
    mkdir("gone", 0777);
    chdir("gone");
    rmdir("../gone");
    printf("gone %d\n", camera_save_image(camera, "x.png", 0));
    fflush(stdout);
    exit(0);
}
int main(void) { robot_live(init); robot_run(run); return 0; }
"""
    out = tmp_path / "out"
    run_controller(c_file(tmp_path, "saver.c", body), duration=0.5, out=out)
    assert capfd.readouterr().out == "saved 0 0\ngone -1\n"  # a removed folder: the simulator's before
    assert sorted(os.listdir(out / "sub")) == ["caf\udce9.png", "here.png"]  # the bytes caf\xe9.png
    assert not (out / "here.png").exists() and not (out / "x.png").exists()


@pytest.mark.slow
def test_a_second_run_compiles_nothing_and_a_changed_source_compiles_again(tmp_path):
    source = c_file(tmp_path, "ctl.c", "int main(void) { robot_live(0); robot_step(8); return 0; }\n")
    first = cbind.compile_controller(source)
    stamp = first.stat().st_mtime_ns
    assert cbind.compile_controller(source) == first and first.stat().st_mtime_ns == stamp
    source.write_text(source.read_text().replace("robot_step(8)", "robot_step(16)"))
    assert cbind.compile_controller(source) != first


def test_a_changed_header_of_the_controllers_own_compiles_again(tmp_path, capfd):
    # Included with quotes from the controller's folder, and from there from a folder beside it.
    folder, shared = tmp_path / "hdr", tmp_path / "inc"
    folder.mkdir()
    shared.mkdir()
    (folder / "hdr.c").write_text(
        '#include <stdio.h>\n#include <device/robot.h>\n#include "val.h"\n'
        'int main(void) { robot_live(0); printf("VAL=%d\\n", VAL); robot_step(8); return 0; }\n'
    )
    (folder / "val.h").write_text('#include "../inc/deep.h"\n#define VAL (DEEP + 1)\n')
    (shared / "deep.h").write_text("#define DEEP 1\n")
    first = cbind.compile_controller(folder)
    assert cbind.compile_controller(folder) == first
    (shared / "deep.h").write_text("#define DEEP 41\n")
    assert cbind.compile_controller(folder) != first
    run_controller(folder, duration=0.05)
    assert "VAL=42" in capfd.readouterr().out


def test_a_compile_error_is_exit_2_with_the_compilers_file_and_line(tmp_path, capsys):
    source = c_file(tmp_path, "broken.c", "int main(void) {\n    robot_live(0)\n    return 0;\n}\n")
    assert main(["run", str(source)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"aibo-sim: error: {source}: compiling failed:\n") and re.search(
        r"broken\.c:6:\d+: error", err
    )


def test_a_file_that_does_not_link_or_is_not_text_is_exit_2_naming_it(tmp_path, capsys):
    empty = c_file(tmp_path, "empty.c", "")
    assert main(["run", str(empty)]) == 2
    assert capsys.readouterr().err.startswith(f"aibo-sim: error: {empty}: linking failed:\n")
    latin = c_file(tmp_path, "latin.c", "int main(void) { return 0; }\n")
    latin.write_bytes(latin.read_bytes() + b'char *s = "\xf3" x;\n')
    assert main(["run", str(latin)]) == 2
    assert capsys.readouterr().err.startswith(f"aibo-sim: error: {latin}: compiling failed:\n")


def test_a_compile_stopped_by_a_signal_stops_the_compilers_whole_process_group(tmp_path):
    """Only the driver (cc) was killed: its cc1 and as outlived aibo-sim, their files left in /tmp."""
    from aibo_sim.cbind import build

    pass_pid = tmp_path / "pass.pid"  # a compiler pass, the driver's child, as cc1 is
    command = ["sh", "-c", f"sleep 60 & echo $! > {pass_pid}; wait"]
    interrupt = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    interrupt.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            build._run(command, tmp_path / "x.c", "compiling")
    finally:
        interrupt.cancel()
    pid = int(pass_pid.read_text())
    with pytest.raises(ProcessLookupError):  # gone (its parent, sh, reaped it: no zombie is left either)
        for _ in range(100):
            os.kill(pid, 0)
            time.sleep(0.02)


def test_no_compiler_is_exit_2_naming_it_and_how_to_install_it(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("CC", "no-such-cc")
    source = c_file(tmp_path, "ctl.c", "int main(void) { return 0; }\n")
    assert main(["run", str(source)]) == 2
    assert capsys.readouterr().err == (
        "aibo-sim: error: no compiler 'no-such-cc' found: this controller needs a C "
        "compiler (Debian/Ubuntu: apt-get install gcc), or set CC\n"
    )
    monkeypatch.setenv("CC", "cc -Wall")  # flags in CC: the compiler is there, the variable is not one
    assert main(["run", str(source)]) == 2
    assert capsys.readouterr().err == (
        "aibo-sim: error: CC='cc -Wall': set CC to the compiler alone ('cc'): aibo-sim gives it its flags\n"
    )


def test_a_crash_is_exit_1_with_the_signal_and_time_and_keeps_run_json_and_frames(tmp_path, capsys):
    source = c_file(
        tmp_path,
        "crash.c",
        "#include <device/camera.h>\nint main(void) {\n  robot_live(0);\n"
        '  camera_enable(robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1"), 32);\n'
        "  robot_step(96);\n  *(volatile int *)0 = 1;\n  return 0;\n}\n",
    )
    out = tmp_path / "out"
    assert main(["run", str(source), "--out", str(out)]) == 1
    assert (
        "controller crash.c at simulated t = 0.096 s: crashed (SIGSEGV: Segmentation fault)" in capsys.readouterr().err
    )
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "failed" and run["simulated_s"] == 0.096 and run["camera_frames"] == 3
    assert sorted(p.name for p in (out / "frames").iterdir()) == ["000000.png", "000001.png", "000002.png"]


@pytest.mark.slow
def test_abort_exit_status_and_api_errors_end_the_run_as_in_python(tmp_path):
    cases = {
        "abort.c": ("int main(void) { robot_live(0); robot_step(8); abort(); }", r"crashed \(SIGABRT"),
        "status.cpp": (
            "int main() { robot_live(0); robot_step(16); exit(3); }",
            r"exited with exit\(3\) at simulated t = 0\.016 s",
        ),
        "tag.c": (
            "int main(void) { robot_live(0); servo_set_position(42, 0.1); robot_step(8); return 0; }",
            r"servo_set_position\(42, 0\.1\) raised DeviceError: invalid device tag 42",
        ),
        "unread.c": (
            "int main(void) { robot_live(0); robot_step(8);\n"
            '  printf("%f", servo_get_position(robot_get_device("PRM:/r1/c1/c2-Joint2:12"))); return 0; }',
            r"servo_get_position\(1\) raised DeviceError: .*not enabled",
        ),
        "disabled.c": (
            'int main(void) { robot_live(0); DeviceTag pan = robot_get_device("PRM:/r1/c1/c2-Joint2:12");\n'
            "  servo_enable_position(pan, 8); robot_step(8); servo_get_position(pan); robot_step(8);\n"
            "  servo_get_position(pan); servo_disable_position(pan); servo_get_position(pan); return 0; }",
            r"servo_get_position\(1\) raised DeviceError: .*not enabled",
        ),  # not the answer given ahead
        "step.c": (
            "int main(void) { robot_live(0); robot_step(12); return 0; }",
            r"robot_step\(12\) raised ValueError: step of 12 ms: must be a positive whole multiple",
        ),
    }
    for name, (body, message) in cases.items():
        with pytest.raises(ControllerFailed, match=message) as failed:
            run_controller(c_file(tmp_path, name, body + "\n"), duration=1)
        if name == "status.cpp":
            assert failed.value.exit_status == 3


def test_what_a_c_controller_printed_before_an_api_error_is_not_lost(tmp_path, capfd):
    """Its standard output, a file or a pipe here (CI, tee), is block-buffered: it was lost when
    the error ended the controller, where the Python controller's print showed."""
    body = 'int main(void) { robot_live(0); robot_step(8); printf("before the error\\n");\n'
    body += "  servo_set_position(42, 0.1); robot_step(8); return 0; }\n"
    with pytest.raises(ControllerFailed, match="invalid device tag 42"):
        run_controller(c_file(tmp_path, "printed.c", body), duration=1)
    assert "before the error\n" in capfd.readouterr().out


def test_the_robot_die_functions_run_after_a_call_that_failed_as_in_python(tmp_path):
    """The controller was killed at the failed call: its robot_die functions, which a Python
    controller's exception runs, did not. Its calls after the failed one are not made (Python's
    raise would not reach them); a robot_die function's own failed call ends it and is reported."""
    body = 'static void save(void) {\n  FILE *f = fopen("results.txt", "w");\n'
    body += '  fprintf(f, "t %g\\n", robot_get_time());\n  fclose(f);\n'
    body += "  robot_step(16);\n  servo_set_position(77, 0.1);\n  robot_step(8);\n"
    body += '  fclose(fopen("not_reached.txt", "w"));\n}\n'
    body += "int main(void) {\n  robot_die(save);\n  robot_step(16);\n  servo_set_position(99, 0.1);\n"
    body += '  robot_step(8);\n  fclose(fopen("not_reached.txt", "w"));\n  return 0;\n}\n'
    with pytest.raises(ControllerFailed) as failed:
        run_controller(c_file(tmp_path, "fails.c", body), duration=1, out=tmp_path / "out")
    message = str(failed.value)
    assert message.startswith("controller fails.c at simulated t = 0.016 s: servo_set_position(99, 0.1) raised")
    assert "\nthen its robot_die function's call servo_set_position(77, 0.1) raised DeviceError" in message
    assert (tmp_path / "out" / "results.txt").read_text() == "t 0.016\n"
    assert not (tmp_path / "out" / "not_reached.txt").exists()


def test_a_failed_call_queued_before_the_end_ends_no_robot_die_function(tmp_path):
    """A failed call queued by main() before it returned, or by a robot_die function before it
    returned, cut the next robot_die function short at its first call (Python runs it whole); a
    crash in a robot_die function after a failed call was not reported."""
    die = 'static void die1(void) {\n  robot_get_device("PRM:/r1/c1-Joint2:11");\n  fclose(fopen("die1.txt", "w"));\n'
    die += "  servo_set_position(1, 1.0 / 0.0);\n}\n"  # queued, then it returns
    die += 'static void die2(void) {\n  robot_get_time();\n  fclose(fopen("die2.txt", "w"));\n'
    die += "  *(volatile int *)0 = 1;\n}\n"
    body = die + "int main(void) {\n  robot_die(die1);\n  robot_die(die2);\n"
    body += "  servo_set_position(99, 0.1);\n  return 0;\n}\n"
    with pytest.raises(ControllerFailed) as failed:
        run_controller(c_file(tmp_path, "queued.c", body), duration=1, out=tmp_path / "out")
    assert str(failed.value).split("\n")[1:] == [
        "then its robot_die function's call servo_set_position(1, inf) raised DeviceError: PRM:/r1/c1-Joint2:11: "
        "position must be a finite number, not inf",
        "then it crashed in a robot_die function (SIGSEGV)",
    ]
    assert "at simulated t = 0.000 s: servo_set_position(99, 0.1) raised DeviceError" in str(failed.value)
    assert (tmp_path / "out" / "die1.txt").exists() and (tmp_path / "out" / "die2.txt").exists()


def test_calls_at_exit_outside_the_robot_die_functions_and_from_the_thread_that_ends(tmp_path, capfd):
    """An atexit handler of the controller's own that steps past the end gets its calls answered
    (it crashed: the robot_die functions' way out was taken); robot_die functions run in the thread
    that ended the controller, which may not be the one that made the calls (they were refused)."""
    own = 'static void settle(void) {\n  robot_step(8);\n  robot_step(8);\n  printf("settled\\n");\n}\n'
    own += "static int run(int ms) { return 8; }\nint main(void) {\n  atexit(settle);\n  robot_run(run);\n}\n"
    worker = '#include <pthread.h>\nstatic void bye(void) { printf("bye t=%.3f\\n", robot_get_time()); }\n'
    worker += "static void *work(void *unused) {\n  (void)unused;\n  robot_die(bye);\n"
    worker += "  for (int i = 0; i < 5; i++) robot_step(8);\n  return 0;\n}\n"
    worker += (
        "int main(void) {\n  pthread_t t;\n  pthread_create(&t, 0, work, 0);\n  pthread_join(t, 0);\n  return 0;\n}\n"
    )
    run_controller(c_file(tmp_path, "own.c", own), duration=0.1)
    run_controller(c_file(tmp_path, "worker.c", worker), duration=1)
    assert capfd.readouterr().out == "settled\nbye t=0.040\n"


def test_console_printf_prints_in_order_with_printf_whole_and_byte_for_byte(tmp_path, capfdbinary):
    """robot_console_printf went through the simulator, which printed it after the controller's
    next printf (B0 A0 ...), cut at 4095 bytes and with other bytes than UTF-8 replaced."""
    body = "int main(void) {\n  static char long_text[6001];\n  memset(long_text, 'x', 6000);\n"
    body += '  for (int n = 0; n < 3; n++) { robot_console_printf("A%d\\n", n); printf("B%d\\n", n); robot_step(8); }\n'
    body += '  robot_console_printf("%s|END caf\\xe9\\n", long_text);\n  return 0;\n}\n'
    run_controller(c_file(tmp_path, "order.c", "#include <string.h>\n" + body), duration=1)
    assert capfdbinary.readouterr().out == b"A0\nB0\nA1\nB1\nA2\nB2\n" + b"x" * 6000 + b"|END caf\xe9\n"


def test_what_a_c_controller_printed_before_it_crashed_is_not_lost(tmp_path, capfd):
    """Its standard output into a file was flushed at its calls only: the line before a crash was lost."""
    body = 'int main(void) {\n  robot_step(8);\n  printf("about to crash\\n");\n  *(volatile int *)0 = 1;\n}\n'
    with pytest.raises(ControllerFailed, match="SIGSEGV"):
        run_controller(c_file(tmp_path, "crash.c", body), duration=1)
    assert capfd.readouterr().out == "about to crash\n"


def test_the_bindings_own_failures_are_named_not_taken_for_the_controllers_exit(tmp_path):
    """A call from a second thread mixed its messages with the first's (wrong answers, the run 'ok'); a
    call too large ended with 'exited with exit(70)', a status the controller never gave."""
    thread = "#include <pthread.h>\nstatic void *other(void *unused) { (void)unused; robot_get_name(); return 0; }\n"
    thread += "int main(void) {\n  pthread_t t;\n  robot_step(8);\n  pthread_create(&t, 0, other, 0);\n"
    thread += "  pthread_join(t, 0);\n  robot_step(8);\n  return 0;\n}\n"
    race = "#include <pthread.h>\nstatic void *other(void *unused) { (void)unused; for (;;) robot_get_time(); }\n"
    race += "int main(void) {\n  pthread_t t;\n  robot_step(8);\n  pthread_create(&t, 0, other, 0);\n"
    race += "  for (;;) robot_step(8);\n}\n"  # the other thread calls while this one waits for its answer
    big = "#include <string.h>\nint main(void) {\n  static char name[70000];\n  memset(name, 'a', sizeof name - 1);\n"
    big += "  mtn_new(name);\n  return 0;\n}\n"
    for name, body, message in (
        ("thread.c", thread, "robot_get_name called from a second thread: a C controller makes its calls from one"),
        *[("race.c", race, "robot_get_time called from a second thread")] * 3,  # a broken pipe, half the time
        ("big.c", "#include <device/mtn.h>\n" + big, "mtn_new: its arguments exceed 65536 bytes"),
    ):
        with pytest.raises(ControllerFailed, match=message) as failed:
            run_controller(c_file(tmp_path, name, body), duration=1)
        assert "exit(" not in str(failed.value)


@pytest.mark.slow
def test_a_controller_that_computes_long_is_announced_as_such(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(cbind.serve, "WAIT_NOTICE_S", 0.2)
    source = c_file(
        tmp_path,
        "busy.c",
        "#include <time.h>\nint main(void) {\n  robot_live(0); robot_step(40);\n"
        "  struct timespec t = {0, 500000000}; nanosleep(&t, 0);\n  robot_step(8); return 0;\n}\n",
    )
    assert run_controller(source, duration=1).simulated_s == 0.048
    assert (
        "aibo-sim: waiting for controller busy.c: no API call for 0.2 s of wall time (simulated time stays at "
        "t = 0.040 s)"
    ) in capsys.readouterr().err


def test_the_headers_settings_are_the_python_apis():
    header = (Path(cbind.__file__).parent / "include" / "device" / "camera.h").read_text()
    defined = {name: int(value) for name, value in re.findall(r"#define (CAMERA_\w+) (\d+)", header)}
    assert defined == {name: getattr(controller, name) for name in dir(controller) if name.startswith("CAMERA_")}
    assert defined["CAMERA_WB_FL"] == ers7_camera.ocamparamWB_FL_MODE


def test_the_headers_setting_constants_are_generated():
    """camera.h's CAMERA_* lines are those ``headers`` makes from Sony's values and the camera
    model's tables (2856 K: ``WHITE_BALANCE_K``), not written by hand."""
    text = headers.CAMERA_H.read_text()
    assert text == headers.camera_header(text), "camera.h is stale: run python -m aibo_sim.cbind.headers"
    text = headers.ROBOT_H.read_text()
    assert text == headers.robot_header(text), "robot.h is stale: run python -m aibo_sim.cbind.headers"
    assert "#define ROBOT_KEYBOARD_LEFT 314\n" in text and "#define ROBOT_KEYBOARD_ALT 0x40000\n" in text
    assert "#define CAMERA_WB_INDOOR 1     /* 2856 K */\n" in headers.camera_constants()
    assert "#define CAMERA_GAIN_MID 2      /* 0 dB, the default */\n" in headers.camera_constants()


def test_a_folder_without_its_main_file_is_refused(tmp_path, capsys):
    folder = tmp_path / "walker"
    folder.mkdir()
    (folder / "other.c").write_text("int main(void) { return 0; }\n")
    assert not cbind.is_c_controller(folder)
    assert main(["run", str(folder)]) == 2
    assert f"{folder}: a folder with no walker.c or walker.cc or walker.cpp" in capsys.readouterr().err


def test_dump_takes_a_c_controller_as_it_takes_its_python_twin(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the tour writes tour.txt where it runs
    for name, path in (("c", TOUR), ("python", TOUR / "api_tour.py")):
        assert (
            main(
                [
                    "dump",
                    str(path),
                    "--out",
                    str(tmp_path / name),
                    "--steps",
                    "6",
                    "--formats",
                    "rgb",
                    "--camera-profile",
                    "ideal",
                ]
            )
            == 0
        )
    frames = sorted((tmp_path / "python" / "rgb").iterdir())
    assert len(frames) == 6
    assert all((tmp_path / "c" / "rgb" / f.name).read_bytes() == f.read_bytes() for f in frames)


def start_long_run(source: Path, out: Path, started: Path):
    """``aibo-sim run source`` for a long time in a process of its own (its stderr piped), once
    ``started`` exists and a little more."""
    import subprocess
    import sys
    import time

    run = subprocess.Popen(
        [sys.executable, "-m", "aibo_sim.cli", "run", str(source), "--duration", "100000", "--out", str(out)],
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while not started.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.3)
    return run


@pytest.mark.slow
def test_ctrl_c_runs_the_c_robot_die_functions_then_exits_130(tmp_path):
    import signal

    source = c_file(
        tmp_path,
        "loop.c",
        'static void bye(void) {\n  FILE *f = fopen("die.txt", "w");\n  fputs("bye\\n", f);\n  fclose(f);\n'
        "  for (;;) robot_step(8);\n}\n"
        'static void then(void) { fclose(fopen("then.txt", "w")); }\n'
        'int main(void) {\n  robot_live(0); robot_die(bye); robot_die(then);\n  fclose(fopen("started.txt", "w"));\n'
        "  for (;;) robot_step(8);\n}\n",
    )
    out = tmp_path / "out"
    run = start_long_run(source, out, out / "started.txt")
    run.send_signal(signal.SIGINT)
    assert run.communicate(timeout=60)[1].endswith("aibo-sim: interrupted\n") and run.returncode == 130
    # its robot_step past the end ended it, as Python's SimulationEnd does (it stepped on, for ever,
    # answered "end" without simulating), and the next one ran
    assert (out / "die.txt").read_text() == "bye\n" and (out / "then.txt").exists()


@pytest.mark.slow
@pytest.mark.parametrize(
    "name, body, started, left",
    [
        (  # a robot_die function looping on robot_get_time kept the run going until a second signal
            "poll.c",
            'static void bye(void) {\n  fclose(fopen("bye.txt", "w"));\n  for (;;) robot_get_time();\n}\n'
            "int main(void) {\n  robot_die(bye);\n  for (;;) robot_step(8);\n}\n",
            "frames",
            "bye.txt",
        ),
        (  # after a failed call the simulator skipped the calls without results before it looked at the signal
            "skips.c",
            'int main(void) {\n  DeviceTag s = robot_get_device("PRM:/r1/c1-Joint2:11");\n'
            '  fclose(fopen("failing.txt", "w"));\n  servo_set_position(999, 0.1);\n'
            "  for (;;) servo_set_position(s, 0.1);\n}\n",
            "failing.txt",
            "failing.txt",
        ),
    ],
)
def test_one_sigterm_ends_a_c_controller_that_calls_for_ever(tmp_path, name, body, started, left):
    """Only silence was cut short (2 s): a controller still calling after SIGTERM ran on (until a
    second signal, or SIGKILL), where a Python controller is stopped STOP_GRACE_S after the first."""
    import signal

    from aibo_sim.exit_status import STOP_GRACE_S

    out = tmp_path / "out"
    run = start_long_run(c_file(tmp_path, name, body), out, out / started)
    run.send_signal(signal.SIGTERM)
    try:
        err = run.communicate(timeout=STOP_GRACE_S + 20)[1]
    finally:
        run.kill()
    assert run.returncode == 143 and (out / left).exists(), err
    assert f"controller {name} still calling {STOP_GRACE_S:g} s after SIGTERM: stopped" in err


@pytest.mark.slow
@pytest.mark.parametrize("signal_name, status", [("SIGINT", 130), ("SIGTERM", 143)])
def test_a_signal_right_after_a_call_is_read_loses_no_call(tmp_path, signal_name, status):
    """The signal comes just after a call was read, before it is answered: a KeyboardInterrupt
    raised there lost the call, and simulator and controller waited for each other forever."""
    import subprocess
    import sys

    source = c_file(
        tmp_path,
        "loop.c",
        'static void bye(void) {\n  FILE *f = fopen("die.txt", "w");\n  fputs("bye\\n", f);\n  fclose(f);\n'
        "  robot_step(8);\n  abort();\n}\n"  # not reached: the step past the end ends the function
        "int main(void) {\n  robot_live(0); robot_die(bye);\n  for (;;) robot_step(8);\n}\n",
    )
    out = tmp_path / "out"
    script = (
        "import signal, sys\n"
        "from aibo_sim.cbind import serve\n"
        "from aibo_sim.cli import main\n"
        "read, reads = serve._Calls._read, []\n"
        "def read_then_signal(calls):\n"
        "    chunk = read(calls)\n"
        "    reads.append(len(chunk))\n"
        f"    if len(reads) == 30:\n        signal.raise_signal(signal.{signal_name})\n"
        "    return chunk\n"
        "serve._Calls._read = read_then_signal\n"
        f"sys.exit(main(['run', {str(source)!r}, '--duration', '100000', '--out', {str(out)!r}]))\n"
    )
    run = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert run.returncode == status, run.stderr
    assert (out / "die.txt").read_text() == "bye\n"


def test_the_wheel_ships_the_headers_and_the_binding():
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+
    patterns = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"][
        "aibo_sim.cbind"
    ]
    package = Path(cbind.__file__).parent
    data = [
        p.relative_to(package).as_posix() for p in package.rglob("*") if p.is_file() and p.suffix not in (".py", ".pyc")
    ]
    assert "include/device/robot.h" in data and "libaibo.c" in data
    assert all(any(fnmatch.fnmatch(name, pattern) for pattern in patterns) for name in data), data


def test_the_simulators_own_failures_in_a_c_controllers_call_are_not_blamed_on_it(tmp_path, monkeypatch, capsys):
    """A divergence (exit 3) or no OpenGL context (exit 2) inside robot_step ends a C controller's
    run as it ends a Python one's (both were 'controller ... raised', exit 1)."""
    from aibo_sim.sim import Simulation, SimulationDiverged

    source = c_file(
        tmp_path,
        "look.c",
        "#include <device/camera.h>\nint main(void) {\n  robot_live(0);\n"
        '  camera_enable(robot_get_device("PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1"), 32);\n'
        "  for (;;) robot_step(32);\n}\n",
    )
    with monkeypatch.context() as patch:

        def diverge(*args, **kwargs):
            raise SimulationDiverged("gone")

        patch.setattr(Simulation, "step_frames", diverge)
        with pytest.raises(SimulationDiverged, match="gone"):
            run_controller(source, duration=1)
    monkeypatch.setenv("MUJOCO_GL", "glfw")
    for variable in ("DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(variable, raising=False)
    assert main(["run", str(source), "--duration", "0.5"]) == 2
    err = capsys.readouterr().err
    assert (
        err.startswith("aibo-sim: error: MUJOCO_GL=glfw: cannot create an OpenGL context") and "controller" not in err
    )


@pytest.mark.parametrize(
    "use, error",
    [
        ("mtn_play(m)", "mtn_play: this MTN was deleted by mtn_delete"),
        ('printf("%d\\n", mtn_is_over(m))', "mtn_is_over: this MTN was deleted by mtn_delete"),
        ("mtn_delete(m)", "mtn_delete: this MTN was deleted by mtn_delete"),
        ("mtn_play((MTN *)&m)", r"mtn_play\(-?0x[0-9a-f]+\): not an MTN"),  # an address cut to an int
    ],
)
def test_a_call_on_a_deleted_motion_is_an_error_that_says_so(tmp_path, use, error):
    # Webots' C API would read freed memory; mtn_is_over's answer robot_step brought ahead too
    # is not used once the motion is deleted.
    body = f"""#include <device/mtn.h>
int main(void) {{
    robot_live(0);
    MTN* m = mtn_new("WALKFWD.MTN");
    mtn_play(m);
    robot_step(8);
    mtn_is_over(m);
    mtn_delete(m);
    {use};
    robot_step(8);
    return 0;
}}
"""
    with pytest.raises(ControllerFailed, match=error):
        run_controller(c_file(tmp_path, "deleted.c", body), duration=1)


def test_motions_made_and_deleted_in_a_loop_and_many_held_at_once_run_on(tmp_path, capfd):
    # Each motion's calls are answered ahead with robot_step: a deleted motion's no longer, and
    # never more than the controller's answer buffer takes (it asks for the rest itself).
    body = r"""#include <device/mtn.h>
int main(void) {
    static MTN* held[1500];
    robot_live(0);
    for (int i = 0; i < 1500; i++) {
        MTN* m = mtn_new("WALKFWD.MTN");
        mtn_is_over(m); mtn_get_time(m); mtn_get_length(m);
        mtn_delete(m);
        robot_step(8);
    }
    for (int i = 0; i < 1500; i++) {
        held[i] = mtn_new("WALKFWD.MTN");
        mtn_is_over(held[i]); mtn_get_time(held[i]); mtn_get_length(held[i]);
    }
    robot_step(8);
    int over = 0;
    for (int i = 0; i < 1500; i++) over += mtn_is_over(held[i]);
    printf("done %d\n", over);
    return 0;
}
"""
    run_controller(c_file(tmp_path, "motions.c", body), duration=20)
    assert "done 1500" in capfd.readouterr().out


def run_cli(source: Path, out: Path, timeout: float = 60):
    """``aibo-sim run source`` in a process of its own; one that hangs is failed after ``timeout``
    and ended by SIGTERM (which stops its controller too)."""
    import subprocess
    import sys

    run = subprocess.Popen(
        [sys.executable, "-m", "aibo_sim.cli", "run", str(source), "--duration", "5", "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        run.stdout_text, run.stderr = run.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        run.terminate()
        pytest.fail(f"aibo-sim run {source.name} hung: {run.communicate(timeout=30)[1]}")
    return run


@pytest.mark.parametrize(
    "handler, message",
    [
        ("  seen = robot_get_time();", "robot_get_time called in a signal handler that interrupted robot_step"),
        ("  exit(0);", "exit() called in a signal handler that interrupted robot_step: the robot_die functions cannot"),
    ],
)
def test_a_call_or_exit_in_a_signal_handler_that_interrupts_a_call_ends_the_run_naming_it(tmp_path, handler, message):
    """The handler waited for the lock its own thread held: the run hung for good."""
    body = "#include <signal.h>\n#include <sys/time.h>\nstatic volatile double seen;\n"
    body += "static void tick(int number) {\n  (void)number;\n" + handler + "\n}\n"
    body += "int main(void) {\n  struct itimerval every = {{0, 1000}, {0, 1000}};\n  signal(SIGALRM, tick);\n"
    body += "  robot_live(0);\n  setitimer(ITIMER_REAL, &every, 0);\n  for (;;) robot_step(8);\n}\n"
    run = run_cli(c_file(tmp_path, "handler.c", body), tmp_path / "out")
    assert run.returncode == 1 and message in run.stderr, run.stderr


def test_a_forked_childs_calls_and_exit_leave_the_controllers_connection_alone(tmp_path):
    """The child's exit ran the robot_die functions, and their calls, on the controller's connection."""
    body = "#include <sys/wait.h>\n#include <unistd.h>\n"
    body += 'static void bye(void) {\n  FILE *f = fopen("died.txt", "a");\n  fprintf(f, "%d\\n", (int)getpid());\n'
    body += "  fclose(f);\n  robot_step(8);\n}\n"
    body += "int main(void) {\n  int status[2];\n  robot_die(bye);\n  robot_step(8);\n"
    body += "  for (int k = 0; k < 2; k++) {\n    pid_t child = fork();\n"
    body += "    if (child == 0) { if (k) robot_get_time(); exit(3); }\n    waitpid(child, &status[k], 0);\n  }\n"
    body += '  FILE *f = fopen("children.txt", "w");\n'
    body += '  fprintf(f, "%d %d %d\\n", (int)getpid(), WEXITSTATUS(status[0]), WEXITSTATUS(status[1]));\n'
    body += "  fclose(f);\n  for (;;) robot_step(8);\n}\n"
    run = run_cli(c_file(tmp_path, "forks.c", body), tmp_path / "out")
    assert run.returncode == 0, run.stderr
    pid, *statuses = (tmp_path / "out" / "children.txt").read_text().split()
    assert statuses == ["3", "70"] and (tmp_path / "out" / "died.txt").read_text() == pid + "\n"
    assert "robot_get_time called in a child process (fork)" in run.stderr


def test_exit_in_a_robot_die_function_goes_on_with_the_next_and_sends_its_calls(tmp_path):
    """exit() in a robot_die function skipped the next one, and the calls it had queued were never made."""
    body = "#include <device/led.h>\nstatic void first(void) {\n  led_set(999, 1);\n  exit(3);\n}\n"
    body += 'static void second(void) {\n  fclose(fopen("second.txt", "w"));\n}\n'
    body += "int main(void) {\n  robot_die(first);\n  robot_die(second);\n  for (;;) robot_step(32);\n}\n"
    with pytest.raises(ControllerFailed) as failed:
        run_controller(c_file(tmp_path, "exits.c", body), duration=0.1, out=tmp_path / "out")
    assert (tmp_path / "out" / "second.txt").exists()
    assert "its robot_die function's call led_set(999, 1) raised DeviceError" in str(failed.value)
    assert "a robot_die function exited with exit(3)" in str(failed.value)


@pytest.mark.parametrize(
    "main_body, message",
    [
        ("robot_die(0);", "robot_die(NULL): the exit function must be callable"),
        ("robot_run(0);", "robot_run(NULL): the run function must be callable"),
        ("robot_run(zero);", "run function returned 0: it must return the next step in ms (e.g. TIME_STEP)"),
        # robot_step(20) raised ... before: a call the controller never made
        ("robot_run(twenty);", "run function returned 20: a step must be a whole multiple of the 8 ms joint frame"),
    ],
)
def test_robot_die_and_robot_run_refuse_what_python_refuses_in_its_words(tmp_path, main_body, message):
    """robot_die(NULL) crashed at the end, robot_run(NULL) at once; a run function returning 0 was
    reported as robot_step(0)'s error. As after Python's exception, the robot_die functions run."""
    body = 'static void bye(void) { fclose(fopen("died.txt", "w")); }\nstatic int zero(int ms) { return 0 * ms; }\n'
    body += "static int twenty(int ms) { return 20 + 0 * ms; }\n"
    body += f"int main(void) {{\n  robot_die(bye);\n  {main_body}\n  for (;;) robot_step(8);\n}}\n"
    with pytest.raises(ControllerFailed) as failed:
        run_controller(c_file(tmp_path, "refused.c", body), duration=0.1, out=tmp_path / "out")
    assert str(failed.value) == f"controller refused.c at simulated t = 0.000 s: {message}"
    assert (tmp_path / "out" / "died.txt").exists()


def test_the_programs_a_controller_runs_inherit_neither_its_connection_nor_its_variables(tmp_path):
    body = '#include <fcntl.h>\nint main(void) {\n  int fd = atoi(getenv("AIBO_SIM_FD"));\n  robot_live(0);\n'
    body += '  FILE *f = fopen("inherited.txt", "w");\n'
    body += '  fprintf(f, "%d %d %d\\n", fcntl(fd, F_GETFD) & FD_CLOEXEC,\n'
    body += '          !getenv("AIBO_SIM_FD"), !getenv("AIBO_SIM_SHM"));\n'
    body += "  fclose(f);\n  return 0;\n}\n"
    run_controller(c_file(tmp_path, "inherits.c", body), duration=0.1, out=tmp_path / "out")
    assert (tmp_path / "out" / "inherited.txt").read_text() == "1 1 1\n"


def test_mtn_get_name_gives_the_files_bytes(tmp_path):
    """The name went out as UTF-8 and was cut at 255 bytes, mid-character."""
    from aibo_sim.mtn import serialize_mtn

    motion = read_mtn(models_dir() / "motions" / "WALKFWD.MTN")
    motion.name = "\xe9" * 200
    (tmp_path / "long.mtn").write_bytes(serialize_mtn(motion))
    body = "#include <string.h>\n#include <device/mtn.h>\nint main(void) {\n"
    body += '  const char *name = mtn_get_name(mtn_new("long.mtn"));\n'
    body += '  FILE *f = fopen("name.bin", "wb");\n  fwrite(name, 1, strlen(name), f);\n  fclose(f);\n  return 0;\n}\n'
    run_controller(c_file(tmp_path, "named.c", body), duration=0.1, out=tmp_path / "out")
    assert (tmp_path / "out" / "name.bin").read_bytes() == b"\xe9" * 200


@pytest.mark.parametrize(
    "die_body, then",
    [
        (
            '  robot_get_device("NoSuchServo");\n',
            "then its robot_die function's call robot_get_device('NoSuchServo') raised DeviceError",
        ),
        ("  robot_die(0);\n", "then robot_die(NULL): the exit function must be callable"),
    ],
)
def test_a_refusal_comes_first_and_a_robot_die_functions_failure_after_it(tmp_path, die_body, then):
    """The die function's failed call was reported alone, as the controller's error (the refusal
    was lost); a second refusal overwrote the first's start, leaving its tail."""
    body = f"static void bye(void) {{\n{die_body}}}\nstatic int calls;\n"
    body += "static int run(int ms) { return ++calls < 3 ? 8 + 0 * ms : 0; }\n"
    body += "int main(void) {\n  robot_die(bye);\n  robot_run(run);\n}\n"
    with pytest.raises(ControllerFailed) as failed:
        run_controller(c_file(tmp_path, "twice.c", body), duration=1, out=tmp_path / "out")
    first, second = str(failed.value).split("\n")
    assert first.endswith(": run function returned 0: it must return the next step in ms (e.g. TIME_STEP)"), first
    assert second.startswith(then), second


def test_exit_in_another_thread_while_the_robot_die_functions_run_waits_for_them(tmp_path):
    """The second thread ran the next robot_die function itself, and the first, stepping past the
    end, jumped into that thread's stack."""
    body = "#include <pthread.h>\n#include <unistd.h>\nstatic pthread_t main_thread;\nstatic volatile int go;\n"
    body += 'static const char *who(void) { return pthread_equal(pthread_self(), main_thread) ? "main" : "worker"; }\n'
    body += "static void *worker(void *unused) {\n  (void)unused;\n  while (!go) usleep(1000);\n  exit(3);\n}\n"
    body += 'static void f1(void) {\n  printf("f1 in %s\\n", who());\n  go = 1;\n  usleep(300000);\n'
    body += '  robot_step(8);\n  printf("not reached\\n");\n}\n'
    body += 'static void f2(void) { printf("f2 in %s\\n", who()); }\n'
    body += "int main(void) {\n  pthread_t t;\n  main_thread = pthread_self();\n  robot_die(f1);\n  robot_die(f2);\n"
    body += "  pthread_create(&t, 0, worker, 0);\n  for (;;) robot_step(64);\n}\n"
    run = run_cli(c_file(tmp_path, "threads.c", body), tmp_path / "out")
    assert run.returncode == 0 and run.stdout_text.splitlines()[:2] == ["f1 in main", "f2 in main"], run.stderr


def test_a_child_forked_before_the_first_call_cannot_call(tmp_path):
    body = "#include <sys/wait.h>\n#include <unistd.h>\nint main(void) {\n  int status;\n  pid_t child = fork();\n"
    body += "  if (child == 0) { robot_get_time(); exit(3); }\n  waitpid(child, &status, 0);\n"
    body += '  FILE *f = fopen("child.txt", "w");\n  fprintf(f, "%d\\n", WEXITSTATUS(status));\n  fclose(f);\n'
    body += "  robot_step(8);\n  return 0;\n}\n"
    run = run_cli(c_file(tmp_path, "early.c", body), tmp_path / "out")
    assert run.returncode == 0 and (tmp_path / "out" / "child.txt").read_text() == "70\n", run.stderr
    assert "robot_get_time called in a child process (fork)" in run.stderr
