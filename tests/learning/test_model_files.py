"""Model files are checked against their config before loading; nothing is unpickled."""

from __future__ import annotations

import json

import pytest

torch = pytest.importorskip("torch")
st = pytest.importorskip("safetensors.torch")

from affordgrasp.cli import main  # noqa: E402
from affordgrasp.errors import InputError  # noqa: E402
from affordgrasp.learning.io import METADATA_KEY, load_model, save_model  # noqa: E402
from affordgrasp.learning.models import build_model  # noqa: E402
from affordgrasp.learning.targets import make_target  # noqa: E402
from affordgrasp.learning.training import default_config  # noqa: E402


def _config(arch="cnn", width=8):
    return default_config(arch, make_target("viable"), n_points=32, width=width)


@pytest.fixture
def good(tmp_path):
    config = _config()
    path = tmp_path / "good.safetensors"
    save_model(path, build_model(config), config)
    return path, config


def _rewrite(path, state, config):
    document = dict(config, format="affordgrasp-model", format_version=1)
    st.save_file(state, str(path), metadata={METADATA_KEY: json.dumps(document)})


def test_a_good_file_loads(good):
    model, config = load_model(good[0])
    assert config["arch"] == "cnn" and not model.training


def test_weights_of_another_architecture_are_refused_naming_the_tensor(good, tmp_path):
    other = build_model(_config("pointnet"))
    path = tmp_path / "other.safetensors"
    _rewrite(path, {k: v.contiguous() for k, v in other.state_dict().items()}, good[1])
    with pytest.raises(InputError, match=r"does not match|has shape .* but its config"):
        load_model(path)


def test_wider_weights_are_refused_with_both_shapes(good, tmp_path):
    wide = build_model(_config(width=16))
    path = tmp_path / "wide.safetensors"
    _rewrite(path, {k: v.contiguous() for k, v in wide.state_dict().items()}, good[1])
    with pytest.raises(InputError, match=r"tensor '.*' has shape \(.*\), but its config"):
        load_model(path)


def test_non_finite_weights_are_refused(good, tmp_path):
    model, config = load_model(good[0])
    state = {k: v.clone().contiguous() for k, v in model.state_dict().items()}
    name = next(k for k, v in state.items() if v.is_floating_point() and v.numel() > 1)
    state[name].view(-1)[0] = float("nan")
    path = tmp_path / "nan.safetensors"
    _rewrite(path, state, config)
    with pytest.raises(InputError, match=rf"tensor '{name}' holds 1 non-finite"):
        load_model(path)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"format_version": 99}, "model format version 99"),
        ({"arch": "transformer"}, "architecture 'transformer'"),
        ({"camera": {"size": 0}}, "input image size 0"),
        ({"target": None}, "no target"),
    ],
)
def test_config_mismatches_are_refused(good, tmp_path, change, message):
    model, config = load_model(good[0])
    path = tmp_path / "changed.safetensors"
    document = {**config, "format": "affordgrasp-model", "format_version": 1, **change}
    state = {k: v.contiguous() for k, v in model.state_dict().items()}
    st.save_file(state, str(path), metadata={METADATA_KEY: json.dumps(document)})
    with pytest.raises(InputError, match=message):
        load_model(path)


def test_a_pickle_is_never_loaded(good, tmp_path):
    path = tmp_path / "pickled.safetensors"
    model, _ = load_model(good[0])
    torch.save(model.state_dict(), path)
    with pytest.raises(InputError, match="is not a safetensors model file"):
        load_model(path)


def test_predict_refuses_a_foreign_model_with_exit_2(good, tmp_path, capsys):
    wide = build_model(_config(width=16))
    path = tmp_path / "wide.safetensors"
    _rewrite(path, {k: v.contiguous() for k, v in wide.state_dict().items()}, good[1])
    code = main(["predict", str(path), str(tmp_path / "no-dataset"), "--out", "p.parquet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith("affordgrasp predict: error: ") and "has shape" in err[0]
