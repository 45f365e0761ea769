"""`satsim.campaign` against `satsim campaign`'s runs.csv (bit for bit), shards, failures."""

from __future__ import annotations

import csv
import shutil
import subprocess

import numpy as np
import pytest

import satsim
from conftest import EXAMPLES, SCENES

# The example campaign, shortened: 8 runs of 2 s, and the duration dispersed so far that some
# draws are negative (those runs fail: failures are data, not errors).
FAILING = """
[[campaign.disperse]]
key = "duration"
uniform = { low = -8.0, high = 0.0 }
"""


def small_campaign_text(failing=False):
    text = (SCENES / "deploy_campaign.toml").read_text()
    text = text.replace("duration = 60.0", "duration = 2.0").replace("runs = 64", "runs = 8")
    assert "duration = 2.0" in text and "runs = 8" in text
    return text + (FAILING if failing else "")


@pytest.fixture()
def scene(tmp_path):
    """The small campaign as a file (its model beside it, as the example's `../satellite.toml`)."""
    (tmp_path / "scenes").mkdir()
    shutil.copy(EXAMPLES / "satellite.toml", tmp_path / "satellite.toml")
    path = tmp_path / "scenes" / "small.toml"
    path.write_text(small_campaign_text(failing=True))
    return path


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def test_campaign_equals_runs_csv_to_the_last_bit(cli, scene, tmp_path):
    subprocess.run([cli, "campaign", scene, "--out", tmp_path / "cli", "--threads", "2"],
                   check=True, capture_output=True)
    with open(tmp_path / "cli" / "runs.csv", newline="") as f:
        rows = list(csv.reader(f))
    header, rows = rows[0], rows[1:]
    c = satsim.campaign(scene, threads=2)
    assert c.columns == header
    assert c.data.shape == (len(rows), len(header)) == (8, len(header))
    assert "failed" in c.status and "ok" in c.status, c.status
    s, m = header.index("status"), header.index("message")
    for i, row in enumerate(rows):
        assert c.status[i] == row[s]
        assert c.messages[i].replace("\n", " ") == row[m]
        want = [np.nan if j == m or not x else
                (1.0 if x == "ok" else 0.0) if j == s else float(x)
                for j, x in enumerate(row)]
        np.testing.assert_array_equal(bits(c.data[i]), bits(want), err_msg=f"run {i}")
    # Columns by name; the text columns as text.
    np.testing.assert_array_equal(c["run"], np.arange(8.0))
    assert list(c["status"]) == c.status
    assert np.isnan(c["final_angle_h4"][~c.ok]).all()
    assert np.isfinite(c["final_angle_h4"][c.ok]).all()


def test_shards_together_are_the_campaign(scene):
    whole = satsim.campaign(scene, threads=1)
    shards = [satsim.campaign(scene, threads=1, shard=(i, 3)) for i in range(3)]
    assert [len(s) for s in shards] == [3, 3, 2]
    assert satsim.campaign(scene, shard="1/3").status == shards[1].status
    data = np.concatenate([s.data for s in shards])
    order = np.argsort(data[:, 0], kind="stable")
    np.testing.assert_array_equal(bits(data[order]), bits(whole.data))
    assert [x for s in shards for x in s.status] == [whole.status[k] for k in
                                                     [0, 3, 6, 1, 4, 7, 2, 5]]


def test_campaign_text_with_base_dir_equals_the_file(scene):
    text = small_campaign_text(failing=True)
    a = satsim.campaign(text, base_dir=scene.parent)
    assert a.columns[0] == "run" and a.columns[-4].startswith("final_")
    assert a.columns[-1] == "stability_held"
    np.testing.assert_array_equal(bits(a.data), bits(satsim.campaign(scene).data))
    assert a.status == satsim.campaign(scene).status


def test_to_pandas_reads_like_runs_csv(scene):
    pd = pytest.importorskip("pandas")
    c = satsim.campaign(scene, shard=(0, 4))
    df = c.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert list(df["run"]) == [0, 4]
    assert list(df["status"]) == c.status


def test_bad_campaign_input(scene):
    with pytest.raises(satsim.SatsimError, match="shard"):
        satsim.campaign(scene, shard=(3, 3))
    with pytest.raises(satsim.SatsimError, match="shard"):
        satsim.campaign(scene, shard="one/two")
    with pytest.raises(satsim.SatsimError, match="threads"):
        satsim.campaign(scene, threads=0)
    bad = small_campaign_text().replace('key = "initial.hinges.angle"',
                                        'key = "initial.hinges.angel"', 1)
    assert bad != small_campaign_text()
    with pytest.raises(satsim.SatsimError, match=r"scenes/<scene text>:\d+: .*initial\.hinges\.angel"):
        satsim.campaign(bad, base_dir=SCENES)


def test_ctrl_c_stops_a_campaign(tmp_path, python_sigint):
    # 2000 runs of 60 s would take minutes: an interrupt 0.5 s in stops every run at its next
    # output row and raises KeyboardInterrupt at once (the bound below is 100 times the time
    # it takes, and far below what the campaign would take were the interrupt seen only at
    # its end).
    import _thread
    import threading
    import time

    text = (SCENES / "deploy_campaign.toml").read_text().replace("runs = 64", "runs = 2000")
    timer = threading.Timer(0.5, _thread.interrupt_main)
    started = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            satsim.campaign(text, base_dir=SCENES, threads=2)
    finally:
        timer.cancel()
    assert time.monotonic() - started < 30.0


def test_runs_held_by_a_stability_limit_warn_as_the_command_line_does(tmp_path):
    """The stiff hinge (56.7 Hz) under DP5(4): every run's steps sit at the method's stability
    limit; `stability_held` says so per run and one warning counts them, in `satsim
    campaign`'s words. Under the scene's own Radau IIA, none."""
    text = (SCENES / "stiff_hinge.toml").read_text()
    text = text.replace("duration = 100.0", "duration = 10.0") + """
[campaign]
runs = 2
seed = 7
[[campaign.disperse]]
key = "initial.base.angular_velocity"
index = 0
normal = { sigma = 0.005 }
"""
    held = text.replace('method = "radau5"', 'method = "dp54"')
    assert held != text
    (tmp_path / "scenes").mkdir()
    shutil.copy(EXAMPLES / "satellite.toml", tmp_path / "satellite.toml")
    with pytest.warns(UserWarning, match="2 of the 2 finished runs took steps held by their explicit"):
        c = satsim.campaign(held, base_dir=tmp_path / "scenes")
    assert list(c["stability_held"]) == [1.0, 1.0]
    import warnings as w

    with w.catch_warnings():
        w.simplefilter("error")
        c = satsim.campaign(text, base_dir=tmp_path / "scenes")
    assert list(c["stability_held"]) == [0.0, 0.0]
    # Stepped by flight software once a second, the integrator's steps are held as before;
    # stepped every 6 ms (below the limit), the period is the step.
    import fsw_controllers as ctl

    with pytest.warns(UserWarning, match="2 of the 2 finished runs took steps held by their explicit"):
        c = satsim.campaign(held, base_dir=tmp_path / "scenes", controller=ctl.nothing, period=1.0)
    assert list(c["stability_held"]) == [1.0, 1.0]
    with w.catch_warnings():
        w.simplefilter("error")
        c = satsim.campaign(held, base_dir=tmp_path / "scenes", controller=ctl.nothing, period=0.006)
    assert list(c["stability_held"]) == [0.0, 0.0]
