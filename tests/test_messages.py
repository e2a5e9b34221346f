"""Small things in messages a user reads."""

import pytest

from ego.params import ConfigError, apply_overrides, describe


def test_a_huge_value_is_named_briefly():
    from ego.scenarios.emergency_brake import EmergencyBrakeConfig

    with pytest.raises(ConfigError) as err:
        apply_overrides(EmergencyBrakeConfig(), {"lead_gap": 1e308})
    assert "1e+308" in str(err.value) and len(str(err.value)) < 120


def test_a_text_parameter_is_described_as_text():
    from ego.control.cascade import CascadePIDParams

    info = {i.name: i for i in describe(CascadePIDParams)}["gains_file"]
    assert info.allowed() == "text"


def test_a_network_that_exists_but_is_not_built_is_not_called_unknown(tmp_path, monkeypatch):
    from ego.sumo import net

    (tmp_path / "road").mkdir()
    (tmp_path / "road" / "road.netccfg").write_text("<configuration/>")
    monkeypatch.setattr(net, "nets_dir", lambda: tmp_path)
    with pytest.raises(ConfigError, match="network 'road' is not built"):
        net.net_file("road")
    with pytest.raises(ConfigError, match=r"unknown network 'lane' \(known: road\)"):
        net.net_file("lane")
