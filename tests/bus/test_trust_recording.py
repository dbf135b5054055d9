"""Issue "trust no input", items 11 and 12: replay of foreign topic names and into the
namespace of a live stack, over a real router."""

from __future__ import annotations

import pytest
import zenoh

from common.transport import zenoh_config
from schemas import Keys
from tests.support.cli import papf
from tests.support.recordings import write_odom_recording, write_ros_topics


@pytest.fixture
def recording(tmp_path):
    return write_odom_recording(tmp_path / "run.mcap")


# -- replay ----------------------------------------------------------------------------------
@pytest.fixture
def ros_recording(tmp_path):
    return write_ros_topics(tmp_path / "ros.mcap")


def test_replay_of_ros_style_topics_maps_them_and_skips_the_impossible(ros_recording, router,
                                                                      session):
    got = []
    sub = session.declare_subscriber("some/**", lambda s: got.append(str(s.key_expr)))
    p = papf("replay", ros_recording, "--rate", "0", "--connect", router)
    sub.undeclare()
    assert p.returncode == 0, p.stderr
    assert f"into the Zenoh router at {router}" in p.stderr
    assert "skipped 3 messages" in p.stderr and "/bad//topic" in p.stderr
    assert got == ["some/topic"] * 3


def test_replay_refuses_a_namespace_where_a_live_stack_runs(recording, router):
    with zenoh.open(zenoh_config("client", [router])) as s:
        token = s.liveliness().declare_token(Keys("rosbot").alive("planner"))
        p = papf("replay", recording, "--rate", "0", "--connect", router)
        assert p.returncode == 2 and "live stack runs in namespace 'rosbot'" in p.stderr
        assert "alive: planner" in p.stderr
        p = papf("replay", recording, "--rate", "0", "--connect", router, "--namespace", "r2")
        assert p.returncode == 0, p.stderr
        p = papf("replay", recording, "--rate", "0", "--connect", router, "--into-live")
        assert p.returncode == 0, p.stderr
        token.undeclare()
