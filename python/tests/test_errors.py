"""Bad input raises `satsim.SatsimError` (a `ValueError`) carrying the command line's message:
the file, the line or the field, what is wrong."""

from __future__ import annotations

import subprocess

import pytest

import satsim
from conftest import EXAMPLES, SCENES

GOOD_MODEL = (EXAMPLES / "satellite.toml").read_text()


def cli_message(cli, *args):
    """The command line's one-line message for bad input (exit status 2), without `error: `."""
    p = subprocess.run([cli, *args], capture_output=True, text=True)
    assert p.returncode == 2, p
    assert p.stdout == ""
    msg = p.stderr.strip()
    assert msg.startswith("error: ")
    return msg[len("error: "):]


def test_satsim_error_is_a_value_error():
    assert issubclass(satsim.SatsimError, ValueError)


def test_unknown_key_names_the_file_and_line(cli, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(GOOD_MODEL.replace("inertia", "intertia", 1))
    line = 1 + GOOD_MODEL[: GOOD_MODEL.index("inertia")].count("\n")
    with pytest.raises(satsim.SatsimError) as e:
        satsim.Model.from_file(bad)
    msg = str(e.value)
    assert msg.startswith(f"{bad}:{line}:") and "intertia" in msg
    assert msg == cli_message(cli, "dynamics", "--model", bad, "--state", EXAMPLES / "state.json")


def test_model_text_errors_name_the_text_and_line():
    text = GOOD_MODEL.replace("mass = 800.0", "mass = -800.0", 1)
    assert text != GOOD_MODEL
    with pytest.raises(satsim.SatsimError, match=r"^<model text>:\d+: .*mass"):
        satsim.Model.from_toml(text)
    with pytest.raises(satsim.SatsimError, match=r"^mine\.toml:\d+: .*mass"):
        satsim.Model.from_toml(text, name="mine.toml")


def test_wrong_state_length_names_the_field(cli, tmp_path):
    state = tmp_path / "short.json"
    state.write_text('{"hinges": {"angle": [0.0, 0.1], "rate": [0, 0, 0, 0, 0]}}')
    m = satsim.Model.from_file(EXAMPLES / "satellite.toml")
    with pytest.raises(satsim.SatsimError) as e:
        m.dynamics(state)
    assert str(e.value) == f"{state}: hinges.angle: expected 5 entries (one per hinge), got 2"
    assert str(e.value) == cli_message(
        cli, "dynamics", "--model", EXAMPLES / "satellite.toml", "--state", state)
    with pytest.raises(satsim.SatsimError, match=r"^<state dict>: hinges\.angle: expected 5"):
        m.dynamics({"hinges": {"angle": [0.0, 0.1], "rate": [0.0] * 5}})
    with pytest.raises(satsim.SatsimError, match=r"^<state text>:1: syntax error"):
        m.dynamics('{"hinges": ')


def test_missing_files(cli, tmp_path):
    missing = tmp_path / "nope.toml"
    with pytest.raises(satsim.SatsimError, match="cannot read the file") as e:
        satsim.Model.from_file(missing)
    assert str(e.value).startswith(str(missing))
    with pytest.raises(satsim.SatsimError, match="cannot read the file"):
        satsim.run(missing)
    m = satsim.Model.from_file(EXAMPLES / "satellite.toml")
    with pytest.raises(satsim.SatsimError, match="nope.json: cannot read the file"):
        m.dynamics(tmp_path / "nope.json")


def test_bad_scene_like_the_command_line(cli, tmp_path):
    scene = tmp_path / "bad.toml"
    text = (SCENES / "two_wings.toml").read_text().replace("duration = 200.0", "duration = -1.0")
    scene.write_text(text.replace('"../two_wings.toml"', f'"{EXAMPLES / "two_wings.toml"}"'))
    with pytest.raises(satsim.SatsimError) as e:
        satsim.run(scene)
    assert str(e.value) == cli_message(cli, "run", scene, "--out", tmp_path / "out")
    assert str(e.value).startswith(f"{scene}:6:") and "duration" in str(e.value)


def test_bad_scene_text():
    with pytest.raises(satsim.SatsimError, match=r"^<scene text>:2: .*unknown key `duraton`"):
        satsim.run('model = "m.toml"\nduraton = 3.0\n')


def test_wrong_argument_types_are_type_errors():
    m = satsim.Model.from_file(EXAMPLES / "satellite.toml")
    with pytest.raises(TypeError):
        m.dynamics(3.0)
    with pytest.raises(TypeError):
        satsim.run(42)
