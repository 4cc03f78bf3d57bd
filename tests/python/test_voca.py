"""The Python module `voca` against the `voca` command line on the EuRoC micro clip.

Every pose comparison is exact: the module's rows are the numbers the CLI writes, so the TUM file the
CLI wrote, read back, must equal them bit for bit (the runs are offline, hence deterministic).

Run by CTest (tests/python.cmake) with PYTHONPATH at the build tree's module and VOCA_BIN at the
`voca` binary; without ../shared/data the session reports CTest's skip code 77 (conftest.py).
"""

import json
import os
import re
import signal
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import voca

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(os.environ.get("VOCA_SHARED_DATA", ROOT.parent / "shared" / "data"))
EUROC = DATA / "euroc_v101_micro" / "mav0"
CALIB = DATA / "calib" / "euroc_ds_calib.json"
OTHER_SIZE_CALIB = DATA / "calib" / "tumvi_512_ds_calib.json"
GROUND_TRUTH = DATA / "trajectories" / "euroc_V1_01_easy.txt"  # the clip is V1_01_easy's start
VOCA = Path(os.environ.get("VOCA_BIN", ROOT / "build" / "release" / "bin" / "voca"))
FRAMES = 40  # a short run: 2 s of the clip, enough for keyframes and the RTE's 6-frame delta

# In the ASan build the interpreter runs with the sanitizer's shared runtime preloaded; the `voca`
# executable carries its own copy, so it must not inherit the preload.
CLI_ENV = {name: value for name, value in os.environ.items() if name != "LD_PRELOAD"}


def run_cli(*args):
    """Runs `voca ARGS`; the completed process (output as text)."""
    return subprocess.run([str(VOCA), *map(str, args)], capture_output=True, text=True, check=False,
                          env=CLI_ENV)


def cli_error(*args):
    """What `voca ARGS` prints after 'error: ' when it fails with bad input (exit code 1)."""
    done = run_cli(*args)
    assert done.returncode == 1, done.stderr
    found = re.search(r"^voca \w+: error: (.*)$", done.stderr, re.MULTILINE)
    assert found, done.stderr
    return found.group(1)


def read_tum(path):
    """The rows of a TUM file as float64, read as Python reads the text (correctly rounded)."""
    lines = Path(path).read_text().splitlines()
    rows = [[float(x) for x in line.split()] for line in lines if not line.startswith("#")]
    return np.array(rows, dtype=np.float64).reshape(-1, 8)


def cli_rows(tmp_path, input_path, *args):
    out = tmp_path / "cli.tum"
    done = run_cli("run", input_path, "--out", out, *args)
    assert done.returncode == 0, done.stderr
    return read_tum(out)


def assert_same_rows(actual, expected):
    assert actual.dtype == np.float64
    assert actual.shape == expected.shape
    # Exact: the same pipeline on the same frames writes the same numbers.
    np.testing.assert_array_equal(actual, expected)


@pytest.fixture(scope="module")
def video(tmp_path_factory):
    """The micro clip encoded by `voca encode` into a VOCA video folder (with calib.json)."""
    folder = tmp_path_factory.mktemp("video") / "euroc-500k"
    done = run_cli("encode", EUROC, "--out", folder, "--calib", CALIB, "--single-pass")
    assert done.returncode == 0, done.stderr
    return folder


def stereo_images():
    """(t_ns, left, right) of the micro clip's raw frames that both cameras have, in time order."""
    def listed(camera):
        rows = (EUROC / camera / "data.csv").read_text().splitlines()
        files = {}
        for row in rows:
            if row.startswith("#") or not row.strip():
                continue
            t_ns, name = row.split(",")
            if (EUROC / camera / "data" / name.strip()).is_file():
                files[int(t_ns)] = EUROC / camera / "data" / name.strip()
        return files

    from PIL import Image

    left, right = listed("cam0"), listed("cam1")
    for t_ns in sorted(set(left) & set(right)):
        yield t_ns, np.asarray(Image.open(left[t_ns])), np.asarray(Image.open(right[t_ns]))


def test_module_describes_itself():
    assert voca.__version__ == run_cli("--version").stdout.split()[-1]
    assert "voca.run" in voca.__doc__ and "voca.Odometry" in voca.__doc__
    for item in (voca.run, voca.evaluate, voca.Odometry, voca.Odometry.push_h264, voca.Odometry.push_gray,
                 voca.Odometry.poll, voca.Odometry.poses, voca.Odometry.finish, voca.VideoFolder, voca.Pose,
                 voca.Error):
        assert item.__doc__ and len(item.__doc__) > 40, item
    assert issubclass(voca.Error, RuntimeError)


def test_run_on_raw_images_equals_cli(tmp_path):
    rows = voca.run(EUROC, CALIB, max_frames=FRAMES)
    assert rows.shape == (FRAMES, 8)
    assert_same_rows(rows, cli_rows(tmp_path, EUROC, "--calib", CALIB, "--frames", FRAMES))
    # The first frame defines the world: identity up to rounding.
    np.testing.assert_allclose(rows[0, 1:], [0, 0, 0, 0, 0, 0, 1], atol=1e-12)


def test_run_on_video_equals_cli_and_returns_summary(tmp_path, video):
    rows, summary = voca.run(video, max_frames=FRAMES, mode="mv_parallel_of", return_summary=True)
    assert_same_rows(rows, cli_rows(tmp_path, video, "--frames", FRAMES, "--mode", "mv_parallel_of"))
    assert summary["frames"] == FRAMES
    assert summary["error"] == "" and summary["failure"] == ""
    assert "mv_parallel_of" in summary["report"]


def test_odometry_push_h264_equals_cli(tmp_path, video):
    folder = voca.VideoFolder(video)
    assert (folder.width, folder.height) == (752, 480)
    assert len(folder) > FRAMES
    assert Path(folder.calibration_file) == video / "calib.json"
    poses = []
    with voca.Odometry(folder.calibration_file) as odometry:
        for index, (t_ns, left, right) in enumerate(folder):
            if index == FRAMES:
                break
            assert isinstance(left, bytes) and left.startswith((b"\0\0\0\1", b"\0\0\1"))  # Annex B
            assert odometry.push_h264(t_ns, left, right)
            while (pose := odometry.poll()) is not None:
                poses.append(pose)
    assert not odometry.running
    while (pose := odometry.poll()) is not None:  # the last ones arrive during finish
        poses.append(pose)
    assert [p.frame_index for p in poses] == list(range(FRAMES))
    rows = np.array([p.tum_row for p in poses])
    assert_same_rows(rows, cli_rows(tmp_path, video, "--frames", FRAMES))
    for pose, row in zip(poses, rows):
        np.testing.assert_array_equal(pose.position, row[1:4])
        assert abs(np.linalg.norm(pose.orientation) - 1.0) < 1e-12
        assert pose.state in ("ok", "reset", "lost")
        assert pose.matrix().shape == (4, 4)
        np.testing.assert_array_equal(pose.matrix()[:3, 3], pose.position)
    assert sum(p.state == "ok" for p in poses) > FRAMES // 2
    assert any(p.keyframe for p in poses)
    assert poses[-1].latency["decode_ms"] > 0 and poses[-1].latency["end_to_end_ms"] > 0


def test_odometry_push_gray_equals_cli_on_raw_images(tmp_path):
    odometry = voca.Odometry(CALIB, input="gray")
    for t_ns, left, right in list(stereo_images())[:FRAMES]:
        assert left.dtype == np.uint8 and left.shape == (480, 752)
        assert odometry.push_gray(t_ns, left, right)
    summary = odometry.finish()
    assert summary["frames"] == FRAMES and summary["error"] == ""
    assert summary["fps"] > 0 and summary["end_to_end_ms"]["p50"] > 0
    assert odometry.finish() == summary  # later calls: the same summary
    rows = odometry.poses()
    assert_same_rows(rows, cli_rows(tmp_path, EUROC, "--calib", CALIB, "--frames", FRAMES))
    assert odometry.poses().shape == (0, 8)  # all were taken


def test_non_contiguous_images_are_copied_not_refused():
    t_ns, left, right = next(stereo_images())
    padded = np.zeros((480, 800), np.uint8)
    padded[:, :752] = left
    with voca.Odometry(CALIB, input="gray") as odometry:
        assert odometry.push_gray(t_ns, padded[:, :752], np.asfortranarray(right))
    assert odometry.poll().frame_index == 0


SHARED_OPTIONS = ("config", "mode", "bridge_iframes", "max_points", "threads", "frontend_threads", "pins",
                  "scheduling", "priority", "lock_memory", "strict", "decoder", "skip_deblock", "trajectory_file",
                  "trajectory_format", "statistics_file", "trace_file", "progress")


def test_odometry_and_run_take_the_same_options_under_the_cli_names(tmp_path, video):
    for function in (voca.Odometry, voca.run):
        for name in SHARED_OPTIONS:
            assert f"\n  {name}=" in function.__doc__, (function, name)
    assert "  max_points=1000 " in voca.run.__doc__ and "  scheduling='other' " in voca.Odometry.__doc__
    # Given to Odometry, options reach the pipeline as the command line's flags do.
    trajectory = tmp_path / "odometry.csv"
    folder = voca.VideoFolder(video)
    with voca.Odometry(folder.calibration_file, mode="none", max_points=300, threads=1,
                       trajectory_file=trajectory, trajectory_format="euroc", bridge_iframes=None) as odometry:
        for _, (t_ns, left, right) in zip(range(FRAMES), folder):
            odometry.push_h264(t_ns, left, right)
    rows = odometry.poses()
    expected = cli_rows(tmp_path, video, "--frames", FRAMES, "--mode", "none", "--max-points", 300, "--threads", 1)
    assert_same_rows(rows, expected)
    assert len(trajectory.read_text().splitlines()) == FRAMES + 1  # EuRoC csv: a header, then a row per pose
    # mode, config and threads by position in voca.run; the rows differ from the default mode's.
    positional = voca.run(video, None, "none", None, None, FRAMES, 0, 1, max_points=300)
    assert_same_rows(positional, expected)
    assert not np.array_equal(positional, voca.run(video, max_frames=FRAMES))


def test_an_unknown_option_or_a_wrong_type_is_a_type_error_naming_it():
    with pytest.raises(TypeError, match=r"voca\.run\(\) got an unexpected keyword argument 'max_point'"):
        voca.run(EUROC, CALIB, max_point=10)
    with pytest.raises(TypeError, match=r"voca\.Odometry\(\): threads takes int, not float"):
        voca.Odometry(CALIB, threads=1.5)
    with pytest.raises(TypeError, match=r"voca\.run\(\): mode takes str, not int"):
        voca.run(EUROC, CALIB, 3)
    with pytest.raises(TypeError, match=r"voca\.Odometry\(\): trajectory_file takes str or os\.PathLike"):
        voca.Odometry(CALIB, trajectory_file=7)


def test_evaluate_equals_cli_json(tmp_path):
    estimate = tmp_path / "est.tum"
    voca.run(EUROC, CALIB, max_frames=FRAMES, trajectory_file=estimate)
    report = tmp_path / "report.json"
    done = run_cli("eval", "--gt", GROUND_TRUTH, "--est", estimate, "--json", report)
    assert done.returncode == 0, done.stderr
    expected = json.loads(report.read_text())
    result = voca.evaluate(GROUND_TRUTH, estimate)
    assert result["associated"] == expected["association"]["pairs"] == FRAMES
    assert result["ate_rmse_m"] == expected["ate"]["rmse"]
    assert result["ate_max_m"] == expected["ate"]["max"]
    assert expected["rte"]["available"] and result["rte_rmse_m"] == expected["rte"]["rmse"]
    assert result["divergent"] is (expected["ate"]["divergent"] or expected["rte"]["divergent"])
    # A working estimate on this easy clip: centimetres, not metres.
    assert 0 < result["ate_rmse_m"] < 0.1


def test_missing_calibration_gives_the_cli_message(tmp_path):
    missing = tmp_path / "no-such-calib.json"
    expected = cli_error("run", EUROC, "--calib", missing, "--out", tmp_path / "x.tum")
    assert str(missing) in expected
    with pytest.raises(voca.Error) as raised:
        voca.Odometry(missing)
    assert str(raised.value) == expected
    assert raised.value.kind == "input"
    with pytest.raises(voca.Error) as raised:
        voca.run(EUROC, missing)
    assert str(raised.value) == expected


def test_wrong_image_size_gives_the_cli_message(tmp_path):
    expected = cli_error("run", EUROC, "--calib", OTHER_SIZE_CALIB, "--out", tmp_path / "x.tum")
    with pytest.raises(voca.Error) as raised:
        voca.run(EUROC, OTHER_SIZE_CALIB)
    assert str(raised.value) == expected
    # Pushed images of the wrong size: the same sentence, for pushed frames.
    sizes = re.compile(r"images are (\d+x\d+) but the calibration (.* )?says (\d+x\d+) for camera 0")
    assert sizes.search(expected).group(1, 3) == ("752x480", "512x512")
    with voca.Odometry(CALIB, input="gray") as odometry:
        small = np.zeros((100, 120), np.uint8)
        with pytest.raises(voca.Error) as raised:
            odometry.push_gray(1, small, small)
        assert sizes.search(str(raised.value)).group(1, 3) == ("120x100", "752x480")
        with pytest.raises(voca.Error, match=r"left image is 120x100 and the right 752x480"):
            odometry.push_gray(1, small, np.zeros((480, 752), np.uint8))
        with pytest.raises(voca.Error, match=r"8-bit gray image .*float64"):
            odometry.push_gray(1, small.astype(np.float64), small)
        assert odometry.running  # bad pushes leave it usable


def test_non_monotonic_time_is_refused_and_the_odometry_goes_on():
    frames = list(stereo_images())[:3]
    with voca.Odometry(CALIB, input="gray") as odometry:
        assert odometry.push_gray(*frames[1])
        for t_ns, left, right in (frames[1], frames[0]):
            with pytest.raises(voca.Error) as raised:
                odometry.push_gray(t_ns, left, right)
            assert str(raised.value) == (f"frame time {t_ns} ns is not after the previous frame's {frames[1][0]} ns; "
                                         "times must increase")
        assert odometry.push_gray(*frames[2])
    assert odometry.poses().shape == (2, 8)


def test_push_after_finish_and_wrong_push_kind(video):
    folder = voca.VideoFolder(video)
    t_ns, left, right = next(folder)
    odometry = voca.Odometry(CALIB)
    with pytest.raises(voca.Error, match="takes H.264 access units"):
        odometry.push_gray(t_ns, np.zeros((480, 752), np.uint8), np.zeros((480, 752), np.uint8))
    with pytest.raises(TypeError, match="expected bytes"):
        odometry.push_h264(t_ns, "not bytes", right)
    assert odometry.push_h264(t_ns, left, right)
    assert odometry.finish()["frames"] == 1
    with pytest.raises(voca.Error) as raised:
        odometry.push_h264(t_ns + 1, *next(folder)[1:])
    assert str(raised.value) == "the odometry has finished: no frame can be pushed after finish()"
    with pytest.raises(voca.Error, match="input: expected h264 or gray, got 'jpeg'"):
        voca.Odometry(CALIB, input="jpeg")
    with pytest.raises(voca.Error, match="data.mp4|mav0|cam0"):
        voca.VideoFolder(EUROC)  # raw images, no videos


def test_a_second_thread_polls_while_one_pushes(tmp_path, video):
    packets = [packet for _, packet in zip(range(FRAMES), voca.VideoFolder(video))]
    odometry = voca.Odometry(video / "calib.json")
    polled = []
    pushed = threading.Event()

    def push():
        for packet in packets:
            odometry.push_h264(*packet)
        pushed.set()

    pusher = threading.Thread(target=push)
    pusher.start()
    while not pushed.is_set() or odometry.running:
        pose = odometry.poll()
        if pose is not None:
            polled.append(pose)
        elif pushed.is_set():
            odometry.finish()
        else:
            time.sleep(0.001)
    pusher.join()
    polled.extend(iter(odometry.poll, None))
    # Every frame once, in order: none lost between the threads, none duplicated.
    assert [p.frame_index for p in polled] == list(range(FRAMES))
    assert_same_rows(np.array([p.tum_row for p in polled]), cli_rows(tmp_path, video, "--frames", FRAMES))


def test_with_block_that_raises_discards_and_reraises(video):
    packets = [packet for _, packet in zip(range(10), voca.VideoFolder(video))]
    with pytest.raises(KeyError):
        with voca.Odometry(video / "calib.json") as odometry:
            for packet in packets:
                odometry.push_h264(*packet)
            raise KeyError("the program's own error")
    assert not odometry.running
    assert odometry.error == ""
    assert len(odometry.poses()) <= 10


def test_run_lets_other_python_threads_go_on():
    ticks = 0
    running = threading.Event()

    def count():
        nonlocal ticks
        while running.is_set():
            ticks += 1
            time.sleep(0.001)

    running.set()
    counter = threading.Thread(target=count)
    counter.start()
    started = time.monotonic()
    voca.run(EUROC, CALIB, max_frames=FRAMES)
    seconds = time.monotonic() - started
    running.clear()
    counter.join()
    # A C++ call holding the GIL stops the counter for its whole length (no bytecode runs to hand the GIL
    # over): a tick or two, before and after. Released, it ticks every ~1 ms sleep (about 500 per second
    # measured on a loaded 2-core machine); a tenth of that leaves room for a slower one.
    assert ticks > 50 * seconds and ticks > 20, (ticks, seconds)


def test_ctrl_c_stops_a_run_cleanly():
    # At the recording's rate the clip takes ~5 s; SIGINT after 0.3 s must end it within a poll (0.1 s)
    # plus the pipeline's drain.
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    started = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        voca.run(EUROC, CALIB, realtime=True)
    timer.join()
    assert time.monotonic() - started < 2.0


def test_a_run_without_any_pose_raises_with_what_was_estimated(tmp_path):
    # Black frames: every frame is lost, which `voca run` reports as an error (exit 1) after writing
    # the repeated poses; voca.run raises with the same message and hands those rows over.
    from PIL import Image

    black = tmp_path / "black" / "mav0"
    for camera in ("cam0", "cam1"):
        (black / camera / "data").mkdir(parents=True)
        rows = ["#timestamp [ns],filename"]
        for i in range(6):
            t_ns = 1_000_000_000 + i * 50_000_000
            Image.fromarray(np.zeros((480, 752), np.uint8)).save(black / camera / "data" / f"{t_ns}.png")
            rows.append(f"{t_ns},{t_ns}.png")
        (black / camera / "data.csv").write_text("\n".join(rows) + "\n")
    out = tmp_path / "black.tum"
    expected = cli_error("run", black, "--calib", CALIB, "--out", out)
    assert expected.startswith("no pose was estimated")
    with pytest.raises(voca.Error) as raised:
        voca.run(black, CALIB)
    assert str(raised.value) == expected
    assert raised.value.summary["lost"] == 6
    assert_same_rows(raised.value.poses, read_tum(out))
