"""Campaigns stepped by your own flight software (contract section 15): `satsim.campaign(scene,
controller=..., period=...)` against `satsim campaign`, byte for byte; workers, executors,
shards, resume, Ctrl-C, failures and metrics."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import fsw_controllers as ctl
import satsim
from conftest import EXAMPLES, ROOT, SCENES

TESTS = Path(__file__).resolve().parent
FILES = ("runs.csv", "traces.csv", "summary.json")

# A run's duration dispersed so far that some draws are negative: those runs fail in the
# scene reader (failures are rows, and must be the command line's rows too).
FAILING = """
[[campaign.disperse]]
key = "duration"
uniform = { low = -8.0, high = 0.0 }
"""


def write_scene(tmp_path: Path, runs: int = 8, duration: float = 2.0, failing: bool = False,
                name: str = "small.toml") -> Path:
    """The example campaign shortened, beside its model as `../satellite.toml`."""
    text = (SCENES / "deploy_campaign.toml").read_text()
    text = text.replace("duration = 60.0", f"duration = {duration}").replace(
        "runs = 64", f"runs = {runs}")
    assert f"duration = {duration}" in text and f"runs = {runs}" in text
    (tmp_path / "scenes").mkdir(exist_ok=True)
    shutil.copy(EXAMPLES / "satellite.toml", tmp_path / "satellite.toml")
    path = tmp_path / "scenes" / name
    path.write_text(text + (FAILING if failing else ""))
    return path


def sensor_scene(tmp_path: Path) -> Path:
    """The flight-software example (gyro, star tracker, discrete controller), 3 s, with a
    campaign dispersing the initial rates: sensor noise drawn from each run's own seed."""
    text = (SCENES / "fsw_in_the_loop.toml").read_text().replace(
        "duration = 600.0", "duration = 3.0")
    text += """
[campaign]
runs = 4
seed = 11
[[campaign.disperse]]
key = "initial.base.angular_velocity"
normal = { sigma = 0.002 }
"""
    (tmp_path / "scenes").mkdir(exist_ok=True)
    shutil.copy(EXAMPLES / "satellite.toml", tmp_path / "satellite.toml")
    path = tmp_path / "scenes" / "sensed.toml"
    path.write_text(text)
    return path


def same_files(a: Path, b: Path) -> None:
    for f in FILES:
        assert (a / f).read_bytes() == (b / f).read_bytes(), f"{f} differs: {a} {b}"


def rows(path: Path):
    with open(path / "runs.csv", newline="") as f:
        r = list(csv.reader(f))
    return r[0], r[1:]


def cli_campaign(cli, scene: Path, out: Path) -> None:
    subprocess.run([cli, "campaign", scene, "--out", out, "--threads", "2"], check=True,
                   capture_output=True)


def test_an_empty_controller_is_the_command_line_campaign_byte_for_byte(cli, tmp_path):
    scene = write_scene(tmp_path, failing=True)
    cli_campaign(cli, scene, tmp_path / "cli")
    res = satsim.campaign(scene, controller=ctl.nothing, period=0.1, out=tmp_path / "py")
    same_files(tmp_path / "cli", tmp_path / "py")
    header, body = rows(tmp_path / "cli")
    assert res.table is res and res.out == str(tmp_path / "py")
    assert res.columns == header and len(res) == 8
    assert 0 < sum(res.ok) < 8, "the scene must have both finished and failed runs"
    for i, r in enumerate(body):
        for j, v in enumerate(r):
            if header[j] not in ("status", "message") and v:
                assert res.data[i, j] == float(v)
    # The same bytes from worker processes, and in memory (no folder).
    for workers in (2, 4):
        w = tmp_path / f"w{workers}"
        satsim.campaign(scene, controller=ctl.nothing, period=0.1, out=w, workers=workers)
        same_files(tmp_path / "cli", w)
    mem = satsim.campaign(scene, controller=ctl.nothing, period=0.1)
    assert mem.out is None
    assert np.array_equal(mem.data.view(np.uint64), res.data.view(np.uint64))
    meta = json.loads((tmp_path / "py" / "campaign.json").read_text())
    assert meta["controller"] == "fsw_controllers:nothing every 0.1 s"


def test_sensor_noise_comes_from_each_runs_seed_as_in_the_command_line(cli, tmp_path):
    scene = sensor_scene(tmp_path)
    cli_campaign(cli, scene, tmp_path / "cli")
    ctl.SEEN.clear()
    satsim.campaign(scene, controller=ctl.recording, period=0.1, out=tmp_path / "py")
    same_files(tmp_path / "cli", tmp_path / "py")
    header, body = rows(tmp_path / "cli")
    assert any(h.startswith("final_gyro_") for h in header)
    # The factory saw each run's drawn values, as runs.csv holds them, and its own seed.
    seen = sorted(ctl.SEEN)
    assert [s[0] for s in seen] == [0, 1, 2, 3]
    dispersed = [h for h in header[1:header.index("status")]]
    for (k, seed, values), r in zip(seen, body):
        assert list(values) == dispersed
        assert [values[c] for c in dispersed] == [float(r[1 + i]) for i in
                                                   range(len(dispersed))]
    assert len({s[1] for s in seen}) == 4
    # Each seed is the one its run's scene carries (`[sensors] seed`), the scene the rows
    # above (equal to the command line's) were made from.
    tomllib = pytest.importorskip("tomllib")
    native = satsim._satsim.NativeCampaign(str(scene))
    for k, seed, _ in seen:
        assert tomllib.loads(native.run_text(k))["sensors"]["seed"] == seed
    ctl.SEEN.clear()
    satsim.campaign(scene, controller=ctl.recording, period=0.1)
    assert sorted(ctl.SEEN) == seen


def test_a_controller_that_fails_fails_its_run_only(tmp_path):
    scene = write_scene(tmp_path, runs=6)
    res = satsim.campaign(scene, controller=ctl.raises_at_run_3, period=0.1)
    assert res.status == ["ok", "ok", "ok", "failed", "ok", "ok"]
    m = res.messages[3]
    assert m.startswith("run 3 at t = 0.5 s: ") and m.endswith("ValueError: boom in run 3"), m
    res = satsim.campaign(scene, controller=ctl.bad, period=0.1)
    assert res.status == ["ok", "failed", "failed", "ok", "failed", "ok"]
    assert "run 1 at t = 0 s" in res.messages[1] and "wheel_q" in res.messages[1]
    assert "wheel_x" in res.messages[2] and "finite" in res.messages[2]
    assert "returned NoneType, not a dict" in res.messages[4]
    res = satsim.campaign(scene, controller=ctl.factory_raises, period=0.1)
    assert res.status.count("failed") == 1
    assert res.messages[2] == "run 2: the controller factory raised RuntimeError: no controller for run 2"


def test_metrics_are_columns_with_their_statistics(tmp_path):
    scene = write_scene(tmp_path, runs=5, failing=True)
    res = satsim.campaign(scene, controller=ctl.pd, period=0.1, metrics=ctl.settling,
                          out=tmp_path / "m")
    header, _ = rows(tmp_path / "m")
    assert header[-2:] == ["peak_rate", "last_h4"]
    ok = res.ok
    assert ok.any() and not ok.all()
    assert np.all(np.isnan(res["peak_rate"][~ok]))
    # The last hinge angle is the statistics' final value; the peak rate is at least the
    # largest of the final rates.
    assert np.array_equal(res["last_h4"][ok], res["final_angle_h4"][ok])
    final = np.sqrt(sum(res[f"final_omega_{a}"] ** 2 for a in "xyz"))
    assert np.all(res["peak_rate"][ok] >= final[ok])
    summary = json.loads((tmp_path / "m" / "summary.json").read_text())
    assert set(summary["peak_rate"]) == {"p1", "p5", "p50", "p95", "p99", "mean", "std"}
    assert summary["last_h4"]["mean"] == pytest.approx(float(np.mean(res["last_h4"][ok])))


def test_shards_merge_into_the_whole_campaign(cli, tmp_path):
    scene = write_scene(tmp_path, failing=True)
    satsim.campaign(scene, controller=ctl.pd, period=0.1, out=tmp_path / "whole",
                    metrics=ctl.settling)
    for i in range(3):
        satsim.campaign(scene, controller=ctl.pd, period=0.1, out=tmp_path / f"s{i}",
                        metrics=ctl.settling, shard=(i, 3))
    subprocess.run([cli, "campaign", "merge", tmp_path / "s0", tmp_path / "s1", tmp_path / "s2",
                    "--out", tmp_path / "merged"], check=True, capture_output=True)
    same_files(tmp_path / "whole", tmp_path / "merged")
    # A built-in controllers' shard is another campaign.
    cli_campaign(cli, scene, tmp_path / "cli")
    p = subprocess.run([cli, "campaign", "merge", tmp_path / "s0", tmp_path / "cli", "--out",
                        tmp_path / "bad"], capture_output=True, text=True)
    assert p.returncode == 2 and "another controller" in p.stderr


def module_cli(*args, **kw):
    env = dict(os.environ, PYTHONPATH=str(TESTS) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    return subprocess.Popen([sys.executable, "-m", "satsim", "campaign", *map(str, args)],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            **kw)


def test_the_command_line_resumes_after_a_kill_to_the_same_bytes(tmp_path):
    scene = write_scene(tmp_path, runs=24, duration=3.0, failing=True)
    whole = module_cli(scene, "--controller", "fsw_controllers:slow", "--period", "0.1",
                       "--out", tmp_path / "whole", "--workers", "2")
    out, err = whole.communicate(timeout=300)
    assert whole.returncode == 0, err
    assert "24 runs:" in out
    p = module_cli(scene, "--controller", "fsw_controllers:slow", "--period", "0.1",
                   "--out", tmp_path / "killed", "--workers", "2", start_new_session=True)
    runs = tmp_path / "killed" / "runs.csv"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if runs.exists() and len(runs.read_text().splitlines()) >= 4:
            break
        time.sleep(0.05)
    os.killpg(p.pid, signal.SIGKILL)
    p.communicate()
    held = len(runs.read_text().splitlines()) - 1
    assert 3 <= held < 24, held
    again = module_cli(scene, "--controller", "fsw_controllers:slow", "--period", "0.1",
                       "--out", tmp_path / "killed", "--workers", "2", "--resume")
    out, err = again.communicate(timeout=300)
    assert again.returncode == 0, err
    same_files(tmp_path / "whole", tmp_path / "killed")
    # Resuming with another controller is refused.
    other = module_cli(scene, "--controller", "fsw_controllers:nothing", "--period", "0.1",
                       "--out", tmp_path / "killed", "--resume")
    out, err = other.communicate(timeout=300)
    assert other.returncode == 2 and "another controller" in err, err


def test_ctrl_c_keeps_every_finished_run_and_resume_goes_on(tmp_path, python_sigint):
    import _thread
    import threading

    scene = write_scene(tmp_path, runs=30, duration=3.0)
    whole = satsim.campaign(scene, controller=ctl.slow, period=0.1, out=tmp_path / "whole")
    timer = threading.Timer(0.5, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt, match="continue with resume=True"):
            satsim.campaign(scene, controller=ctl.slow, period=0.1, out=tmp_path / "cut")
    finally:
        timer.cancel()
    _, held = rows(tmp_path / "cut")
    assert 0 < len(held) < 30
    again = satsim.campaign(scene, controller=ctl.slow, period=0.1, out=tmp_path / "cut",
                            resume=True)
    same_files(tmp_path / "whole", tmp_path / "cut")
    assert np.array_equal(again.data.view(np.uint64), whole.data.view(np.uint64))


def test_ctrl_c_stops_the_worker_processes(tmp_path):
    scene = write_scene(tmp_path, runs=40, duration=2.0)
    p = module_cli(scene, "--controller", "fsw_controllers:slow", "--period", "0.1",
                   "--out", tmp_path / "cut", "--workers", "2")
    runs = tmp_path / "cut" / "runs.csv"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (runs.exists() and
                                                len(runs.read_text().splitlines()) >= 3):
        time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 130, err
    assert "continue with resume=True" in err
    held = len(runs.read_text().splitlines()) - 1
    assert 2 <= held < 40


def test_on_a_dask_cluster_the_files_are_the_same(tmp_path, monkeypatch):
    pytest.importorskip("dask.distributed", reason="needs `pip install dask distributed`")
    from dask.distributed import Client, LocalCluster

    scene = write_scene(tmp_path, runs=6, failing=True)
    satsim.campaign(scene, controller=ctl.pd, period=0.1, metrics=ctl.settling,
                    out=tmp_path / "here")
    # The workers import the controllers' module as this process does.
    monkeypatch.setenv("PYTHONPATH", str(TESTS) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        satsim.campaign(scene, controller=ctl.pd, period=0.1, metrics=ctl.settling,
                        out=tmp_path / "dask", executor=client.get_executor())
    same_files(tmp_path / "here", tmp_path / "dask")


def test_bad_arguments_are_refused_before_any_run(tmp_path):
    scene = write_scene(tmp_path, runs=2)
    with pytest.raises(satsim.SatsimError, match="period"):
        satsim.campaign(scene, controller=ctl.nothing, period=0.0)
    with pytest.raises(satsim.SatsimError, match="control instants"):
        satsim.campaign(scene, controller=ctl.nothing, period=1e-9)
    with pytest.raises(satsim.SatsimError, match="needs period"):
        satsim.campaign(scene, controller=ctl.nothing)
    with pytest.raises(satsim.SatsimError, match="needs controller="):
        satsim.campaign(scene, out=tmp_path / "x")
    with pytest.raises(satsim.SatsimError, match="give workers="):
        satsim.campaign(scene, controller=ctl.nothing, period=0.1, threads=2)
    with pytest.raises(satsim.SatsimError, match="importable"):
        satsim.campaign(scene, controller=lambda run: ctl.Nothing(), period=0.1, workers=2)


def test_on_a_local_ray_cluster_the_files_are_the_same(tmp_path, monkeypatch):
    if os.environ.get("SATSIM_REQUIRE_RAY") != "1":
        pytest.importorskip("ray", reason="needs `pip install ray` (the `ray` extra)")
    import ray

    from satsim.executors import RayExecutor

    scene = write_scene(tmp_path, runs=6, failing=True)
    satsim.campaign(scene, controller=ctl.pd, period=0.1, metrics=ctl.settling,
                    out=tmp_path / "here")
    # The workers import the controllers' module as this process does.
    monkeypatch.setenv("PYTHONPATH", str(TESTS) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    monkeypatch.setenv("RAY_AUTH_MODE", "disabled")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        satsim.campaign(scene, controller=ctl.pd, period=0.1, metrics=ctl.settling,
                        out=tmp_path / "ray", executor=RayExecutor())
    finally:
        ray.shutdown()
    same_files(tmp_path / "here", tmp_path / "ray")
