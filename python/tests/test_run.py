"""`satsim.run` against `satsim run`: the same trajectory to the last bit, the same CSV file."""

from __future__ import annotations

import csv
import subprocess

import numpy as np
import pytest

import satsim
from conftest import EXAMPLES, SCENES

# magnetic_torquer.toml needs the effect that examples/custom_effect.rs registers in Rust:
# neither the Python module nor the `satsim` binary knows it (by design: a plug-in).
SCENE_FILES = sorted(p for p in SCENES.glob("*.toml") if p.stem != "magnetic_torquer")


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    # Rust prints shortest round-trip decimals: float() reads back the same bits.
    return rows[0], np.array([[float(x) for x in r] for r in rows[1:]], dtype=np.float64)


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def test_the_example_scenes_are_found():
    assert any(p.name == "deploy.toml" for p in SCENE_FILES)


@pytest.mark.parametrize("scene", SCENE_FILES, ids=lambda p: p.stem)
def test_run_equals_the_command_line_to_the_last_bit(cli, tmp_path, scene):
    subprocess.run([cli, "run", scene, "--out", tmp_path / "cli"], check=True,
                   capture_output=True)
    columns, data = read_csv(tmp_path / "cli" / "trajectory.csv")
    r = satsim.run(scene)
    assert r.columns == columns
    assert r.data.dtype == np.float64 and r.data.shape == data.shape
    np.testing.assert_array_equal(bits(r.data), bits(data))


def test_out_writes_the_command_lines_csv_byte_for_byte(cli, tmp_path):
    scene = SCENES / "two_wings.toml"
    subprocess.run([cli, "run", scene, "--out", tmp_path / "cli"], check=True,
                   capture_output=True)
    satsim.run(scene, out=tmp_path / "py")
    assert (tmp_path / "py" / "trajectory.csv").read_bytes() == (
        tmp_path / "cli" / "trajectory.csv").read_bytes()


def test_out_none_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    satsim.run(SCENES / "tumbling.toml")
    assert list(tmp_path.iterdir()) == []


def test_columns_by_name_and_contract_columns():
    r = satsim.run(SCENES / "deploy.toml")
    for c in ["t", "q_w", "q_x", "q_y", "q_z", "omega_x", "omega_y", "omega_z",
              "angle_h4", "rate_h4", "kinetic_energy", "h_x", "h_y", "h_z"]:
        assert c in r
    a = r["angle_h4"]
    assert a.ndim == 1 and len(a) == len(r) == r.data.shape[0]
    np.testing.assert_array_equal(a, r.data[:, r.columns.index("angle_h4")])
    np.testing.assert_array_equal(r.t, np.arange(0.0, 301.0, 1.0))
    # The deployment: h4 starts folded at pi and latches at 0.
    assert a[0] == pytest.approx(3.14159) and abs(a[-1]) < 1e-6
    with pytest.raises(KeyError, match="no column 'angle_h9'"):
        r["angle_h9"]


def test_scene_text_is_run_like_the_file():
    scene = SCENES / "two_wings.toml"
    from_file = satsim.run(scene)
    from_text = satsim.run(scene.read_text(), base_dir=SCENES)
    assert from_text.columns == from_file.columns
    np.testing.assert_array_equal(bits(from_text.data), bits(from_file.data))


def test_inline_scene_text_without_files():
    text = """
duration = 10.0
[model]
[[model.body]]
name = "bus"
mass = 10.0
inertia = [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]]
[initial]
base = { angular_velocity = [0.0, 0.3, 0.0] }
[integrator]
method = "rk4"
step = 0.01
[output]
every = 1.0
"""
    r = satsim.run(text)
    # A spin about a principal axis stays one: omega constant, energy 0.5 * 2 * 0.3^2.
    np.testing.assert_allclose(r["omega_y"], 0.3, rtol=0, atol=1e-15)
    np.testing.assert_allclose(r["kinetic_energy"], 0.09, rtol=1e-14)
    assert len(r) == 11


def test_to_pandas():
    pd = pytest.importorskip("pandas")
    r = satsim.run(SCENES / "tumbling.toml")
    df = r.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == r.columns
    np.testing.assert_array_equal(df["t"].to_numpy(), r["t"])


def test_example_model_path_with_run(tmp_path):
    # A scene file written by the user, pointing at a model by a relative path.
    (tmp_path / "m.toml").write_text((EXAMPLES / "satellite.toml").read_text())
    (tmp_path / "s.toml").write_text(
        'model = "m.toml"\nduration = 2.0\n[output]\nevery = 1.0\nplots = false\n'
        "[initial.hinges]\nangle = [0.0, 0.0, 0.0, 0.5, -0.5]\n"
        "rate = [0.0, 0.0, 0.0, 0.0, 0.0]\n")
    r = satsim.run(tmp_path / "s.toml")
    assert r.columns[:8] == ["t", "q_w", "q_x", "q_y", "q_z", "omega_x", "omega_y", "omega_z"]
    np.testing.assert_array_equal(r.t, [0.0, 1.0, 2.0])


def test_ctrl_c_stops_a_run(tmp_path, python_sigint):
    # The run checks for signals while it computes: an interrupt stops it before it ends, so
    # the trajectory it would have written at the end never appears. (Were the interrupt seen
    # only after the call, the run would have finished and written trajectory.csv first.)
    import _thread
    import threading

    text = (SCENES / "deploy.toml").read_text().replace("duration = 300.0", "duration = 3000.0")
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            satsim.run(text, out=tmp_path / "out", base_dir=SCENES)
    finally:
        timer.cancel()
    assert not (tmp_path / "out" / "trajectory.csv").exists()


def test_a_run_that_fails_part_way_keeps_its_rows(cli, tmp_path):
    # A step limit stops the run part-way: the command line exits 1 with the rows up to the
    # failure in its CSV; Python raises SatsimError with the same rows in `partial`.
    (tmp_path / "m.toml").write_text((EXAMPLES / "satellite.toml").read_text())
    scene = tmp_path / "s.toml"
    scene.write_text(
        'model = "m.toml"\nduration = 100.0\n[integrator]\nmethod = "dp54"\nmax_steps = 40\n'
        "[output]\nevery = 0.5\nplots = false\n"
        "[initial]\nbase = { angular_velocity = [0.0, 0.02, 0.01] }\n"
        "hinges = { angle = [0.0, 0.0, 0.0, 0.5, -0.5], rate = [0.1, 0.0, 0.0, 0.2, 0.3] }\n"
        "[effects.hinge_springs]\nstiffness = [50.0, 50.0, 50.0, 2.0, 2.0]\n")
    p = subprocess.run([cli, "run", scene, "--out", tmp_path / "cli"], capture_output=True)
    assert p.returncode == 1, p
    columns, data = read_csv(tmp_path / "cli" / "trajectory.csv")
    assert 0 < len(data) < 201
    with pytest.raises(satsim.SatsimError, match=r"the run failed: .*rows up to t = ") as e:
        satsim.run(scene)
    partial = e.value.partial
    assert isinstance(partial, satsim.Trajectory)
    assert partial.columns == columns
    np.testing.assert_array_equal(bits(partial.data), bits(data))


def test_read_trajectory_reads_what_run_wrote(tmp_path):
    r = satsim.run(SCENES / "libration.toml", out=tmp_path / "out")
    back = satsim.read_trajectory(tmp_path / "out" / "trajectory.csv")
    assert back.columns == r.columns
    np.testing.assert_array_equal(back.data, r.data)


def test_read_trajectory_leaves_out_a_row_cut_by_a_kill(tmp_path):
    # SIGKILL while a row is being written leaves the file ending mid-row: the whole rows
    # before it are read, with a warning naming the line.
    r = satsim.run(SCENES / "libration.toml", out=tmp_path / "out")
    text = (tmp_path / "out" / "trajectory.csv").read_text()
    lines = text.splitlines(keepends=True)
    cut = "".join(lines[:6]) + lines[6][: len(lines[6]) // 2]
    (tmp_path / "cut.csv").write_text(cut)
    with pytest.warns(UserWarning, match=r"cut\.csv:7: the last line has no line end"):
        back = satsim.read_trajectory(tmp_path / "cut.csv")
    assert len(back) == 5
    np.testing.assert_array_equal(back.data, r.data[:5])


def test_read_trajectory_bad_input(tmp_path):
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(satsim.SatsimError, match="the file is empty"):
        satsim.read_trajectory(tmp_path / "empty.csv")
    (tmp_path / "short.csv").write_text("t,a\n0,1\n1\n")
    with pytest.raises(satsim.SatsimError, match=r"short\.csv:3: 1 fields, the header has 2"):
        satsim.read_trajectory(tmp_path / "short.csv")
    (tmp_path / "text.csv").write_text("t,a\n0,x\n")
    with pytest.raises(satsim.SatsimError, match=r"text\.csv:2: `x` in column `a`"):
        satsim.read_trajectory(tmp_path / "text.csv")


def test_a_bad_instructions_cap_is_warned_about_and_ignored():
    # The library cannot refuse SATSIM_INSTRUCTIONS as the command line does: it says so
    # once on standard error and gives the same bits as without it.
    import os
    import sys

    scene = SCENES / "deploy.toml"
    text = scene.read_text().replace("duration = 300.0", "duration = 5.0", 1)
    code = (
        "import sys, satsim, numpy as np\n"
        f"r = satsim.run({text!r}, base_dir={str(SCENES)!r})\n"
        "assert r.data.shape[0] > 1\n"
        "sys.stdout.write(np.ascontiguousarray(r.data).tobytes().hex())\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "SATSIM_INSTRUCTIONS"}
    plain = subprocess.run([sys.executable, "-c", code], env=env, check=True,
                           capture_output=True, text=True)
    bad = subprocess.run([sys.executable, "-c", code],
                         env={**env, "SATSIM_INSTRUCTIONS": "sse9"}, check=True,
                         capture_output=True, text=True)
    assert bad.stdout == plain.stdout
    assert "SATSIM_INSTRUCTIONS" in bad.stderr and "`sse9`" in bad.stderr
    assert bad.stderr.count("warning") == 1
    assert "warning" not in plain.stderr
