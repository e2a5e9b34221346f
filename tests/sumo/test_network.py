"""The shipped motorway network: built from its plain XML, and what it must be."""

import pytest
import sumolib

from ego.sumo.net import build_network, net_file, network_body


@pytest.fixture(scope="module")
def net():
    return sumolib.net.readNet(str(net_file("highway")))


def test_committed_network_matches_a_rebuild(tmp_path):
    rebuilt = build_network("highway", output=tmp_path / "highway.net.xml")
    assert network_body(rebuilt) == network_body(net_file("highway"))


def test_three_lanes_of_3_5_m_at_least_2_km(net):
    edges = [e for e in net.getEdges() if not e.isSpecial()]
    assert len(edges) == 1
    edge = edges[0]
    assert edge.getLaneNumber() == 3
    assert edge.getLength() >= 2000.0
    for lane in edge.getLanes():
        assert lane.getWidth() == pytest.approx(3.5)


def test_lanes_are_straight_and_centred(net):
    # spreadType="center": lane centre lines at y = -3.5 (right), 0 (middle), +3.5 (left)
    edge = net.getEdge("motorway")
    for index, y in [(0, -3.5), (1, 0.0), (2, 3.5)]:
        shape = edge.getLane(index).getShape()
        assert len(shape) == 2
        assert all(p[1] == pytest.approx(y) for p in shape)
        assert shape[1][0] > shape[0][0]  # driving towards +x
