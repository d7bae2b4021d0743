"""C and C++ controllers: the Webots-era headers, compiled with the system compiler, bound to
the running simulation through the Python API."""

import json
import re
import shutil
from pathlib import Path

import pytest

from aibo_sim import cbind, controller
from aibo_sim.cli import main
from aibo_sim.runner import ControllerFailed, run_controller
from openr_bridge import ers7_camera

ROOT = Path(__file__).resolve().parents[1]
TOUR = ROOT / "tests" / "controllers" / "api_tour"
ANNEX_C, ANNEX_PY = ROOT / "controllers" / "annex_capture_c", ROOT / "controllers" / "annex_capture.py"

pytestmark = pytest.mark.skipif(not (shutil.which("cc") and shutil.which("c++")), reason="needs cc and c++")


@pytest.fixture(autouse=True)
def own_cache(tmp_path_factory, monkeypatch):
    """Each test session compiles into its own cache (the user's is left alone)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path_factory.getbasetemp() / "cache"))


def c_file(tmp_path, name: str, body: str) -> Path:
    path = tmp_path / name
    path.write_text("#include <stdio.h>\n#include <stdlib.h>\n#include <device/robot.h>\n#include <device/servo.h>\n"
                    + body)
    return path


def test_every_api_function_gives_in_c_what_it_gives_in_python(tmp_path):
    """The tour calls every function (reset, run, die; enable, disable; a failed and a
    case-insensitive mtn_new) and writes each result; the C and Python twins agree line for
    line, and their trajectories and camera frames are identical."""
    runs = {}
    for name, path in (("c", TOUR), ("python", TOUR / "api_tour.py")):
        runs[name] = run_controller(path, duration=0.5, out=tmp_path / name, camera_profile="ideal")
    tour = (tmp_path / "c" / "tour.txt").read_text()
    assert tour == (tmp_path / "python" / "tour.txt").read_text()
    assert "missing 1 error File not found: no_such_motion.mtn" in tour and "walk a_walk#walk_fwd length 320" in tour
    assert tour.count("\nt ") == 8 and tour.endswith("die at 0.504\n")
    assert runs["c"].robot_xy_yaw == runs["python"].robot_xy_yaw and runs["c"].camera_frames == 15
    for frame in sorted((tmp_path / "python" / "frames").iterdir()):
        assert (tmp_path / "c" / "frames" / frame.name).read_bytes() == frame.read_bytes(), frame.name


@pytest.mark.parametrize("backend", ["sim", "openr"])
def test_annex_i_in_cpp_writes_the_python_ports_image_raw_byte_for_byte(tmp_path, backend):
    images = []
    for name, path in (("cpp", ANNEX_C), ("python", ANNEX_PY)):
        assert main(["run", str(path), "--duration", "5.2", "--backend", backend, "--out", str(tmp_path / name)]) == 0
        images.append((tmp_path / name / "image.raw").read_bytes())
    assert len(images[0]) == 208 * 160 * 3 and images[0] == images[1]


def test_a_second_run_compiles_nothing_and_a_changed_source_compiles_again(tmp_path):
    source = c_file(tmp_path, "ctl.c", "int main(void) { robot_live(0); robot_step(8); return 0; }\n")
    first = cbind.compile_controller(source)
    stamp = first.stat().st_mtime_ns
    assert cbind.compile_controller(source) == first and first.stat().st_mtime_ns == stamp
    source.write_text(source.read_text().replace("robot_step(8)", "robot_step(16)"))
    assert cbind.compile_controller(source) != first


def test_a_compile_error_is_exit_2_with_the_compilers_file_and_line(tmp_path, capsys):
    source = c_file(tmp_path, "broken.c", "int main(void) {\n    robot_live(0)\n    return 0;\n}\n")
    assert main(["run", str(source)]) == 2
    assert re.search(r"broken\.c:6:\d+: error", capsys.readouterr().err)


def test_no_compiler_is_exit_2_naming_it_and_how_to_install_it(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("CC", "no-such-cc")
    source = c_file(tmp_path, "ctl.c", "int main(void) { return 0; }\n")
    assert main(["run", str(source)]) == 2
    assert capsys.readouterr().err == ("aibo-sim: error: no compiler 'no-such-cc' found: this controller needs a C "
                                       "compiler (Debian/Ubuntu: apt-get install gcc), or set CC\n")


def test_a_crash_is_exit_1_with_the_signal_and_time_and_keeps_run_json_and_frames(tmp_path, capsys):
    source = c_file(tmp_path, "crash.c", "#include <device/camera.h>\nint main(void) {\n  robot_live(0);\n"
                    "  camera_enable(robot_get_device(\"PRM:/r1/c1/c2/c3/i1-FbkImageSensor:F1\"), 32);\n"
                    "  robot_step(96);\n  *(volatile int *)0 = 1;\n  return 0;\n}\n")
    out = tmp_path / "out"
    assert main(["run", str(source), "--out", str(out)]) == 1
    assert "controller crash.c: crashed (SIGSEGV: Segmentation fault) at simulated t = 0.096 s" in capsys.readouterr().err
    run = json.loads((out / "run.json").read_text())
    assert run["status"] == "failed" and run["simulated_s"] == 0.096 and run["camera_frames"] == 3
    assert sorted(p.name for p in (out / "frames").iterdir()) == ["000000.png", "000001.png", "000002.png"]


def test_abort_exit_status_and_api_errors_end_the_run_as_in_python(tmp_path):
    cases = {
        "abort.c": ("int main(void) { robot_live(0); robot_step(8); abort(); }", r"crashed \(SIGABRT"),
        "status.cpp": ("int main() { robot_live(0); robot_step(16); exit(3); }", r"exited with exit\(3\) at simulated t = 0\.016 s"),
        "tag.c": ("int main(void) { robot_live(0); servo_set_position(42, 0.1); robot_step(8); return 0; }",
                  r"servo_set_position\(42, 0\.1\) raised DeviceError: invalid device tag 42"),
        "step.c": ("int main(void) { robot_live(0); robot_step(12); return 0; }",
                   r"robot_step\(12\) raised ValueError: step of 12 ms: must be a positive whole multiple"),
    }
    for name, (body, message) in cases.items():
        with pytest.raises(ControllerFailed, match=message) as failed:
            run_controller(c_file(tmp_path, name, body + "\n"), duration=1)
        if name == "status.cpp":
            assert failed.value.exit_status == 3


def test_a_controller_that_computes_long_is_announced_as_such(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(cbind.serve, "WAIT_NOTICE_S", 0.2)
    source = c_file(tmp_path, "busy.c", "#include <time.h>\nint main(void) {\n  robot_live(0); robot_step(40);\n"
                    "  struct timespec t = {0, 500000000}; nanosleep(&t, 0);\n  robot_step(8); return 0;\n}\n")
    assert run_controller(source, duration=1).simulated_s == 0.048
    assert ("aibo-sim: waiting for controller busy.c: no API call for 0.2 s of wall time (simulated time stays at "
            "t = 0.040 s)") in capsys.readouterr().err


def test_the_headers_settings_are_the_python_apis():
    header = (Path(cbind.__file__).parent / "include" / "device" / "camera.h").read_text()
    defined = {name: int(value) for name, value in re.findall(r"#define (CAMERA_\w+) (\d+)", header)}
    assert defined == {name: getattr(controller, name) for name in dir(controller) if name.startswith("CAMERA_")}
    assert defined["CAMERA_WB_FL"] == ers7_camera.ocamparamWB_FL_MODE


def test_a_folder_without_its_main_file_is_refused(tmp_path, capsys):
    folder = tmp_path / "walker"
    folder.mkdir()
    (folder / "other.c").write_text("int main(void) { return 0; }\n")
    assert not cbind.is_c_controller(folder)
    assert main(["run", str(folder)]) == 2
    assert "no such controller file" in capsys.readouterr().err


def test_dump_takes_a_c_controller_as_it_takes_its_python_twin(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the tour writes tour.txt where it runs
    for name, path in (("c", TOUR), ("python", TOUR / "api_tour.py")):
        assert main(["dump", str(path), "--out", str(tmp_path / name), "--steps", "6", "--formats", "rgb",
                     "--camera-profile", "ideal"]) == 0
    frames = sorted((tmp_path / "python" / "rgb").iterdir())
    assert len(frames) == 6
    assert all((tmp_path / "c" / "rgb" / f.name).read_bytes() == f.read_bytes() for f in frames)


def test_ctrl_c_runs_the_c_robot_die_functions_then_exits_130(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    source = c_file(tmp_path, "loop.c", "static void bye(void) {\n  FILE *f = fopen(\"die.txt\", \"w\");\n"
                    "  fprintf(f, \"%d\\n\", robot_step(8));\n  fclose(f);\n}\n"
                    "int main(void) {\n  robot_live(0); robot_die(bye);\n  fclose(fopen(\"started.txt\", \"w\"));\n"
                    "  for (;;) robot_step(8);\n}\n")
    out = tmp_path / "out"
    run = subprocess.Popen([sys.executable, "-m", "aibo_sim.cli", "run", str(source), "--duration", "100000", "--out",
                            str(out)], stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not (out / "started.txt").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.3)
    run.send_signal(signal.SIGINT)
    assert run.communicate(timeout=60)[1].endswith("aibo-sim: interrupted\n") and run.returncode == 130
    assert (out / "die.txt").read_text() == "0\n"  # its robot_step past the end returned, as in Python
