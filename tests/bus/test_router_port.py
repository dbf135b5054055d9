"""``papf run``'s embedded router: a port taken between its choice and the listen (two runs
started at the same instant both saw 7447 free) is chosen again; a port the user named is not."""

from __future__ import annotations

import socket

from papf.launch import run as runmod
from papf.launch.run import RunConfig, open_router
from papf.launch.supervisor import free_port


def test_a_router_port_taken_as_the_run_starts_is_chosen_again(monkeypatch):
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen()
        taken, free = held.getsockname()[1], free_port()
        picks = iter([taken, free])
        monkeypatch.setattr(runmod, "router_port", lambda port: next(picks))
        router, graph, why = open_router(RunConfig(world="open"))
        assert router is not None, why
        try:
            assert why == "" and graph.connect[0] == f"tcp/127.0.0.1:{free}"
            assert all(f":{free}" in " ".join(argv) for argv in graph.nodes.values())
        finally:
            router.close()


def test_a_port_the_user_named_is_not_swapped_for_another():
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen()
        taken = held.getsockname()[1]
        router, graph, why = open_router(RunConfig(world="open", port=taken))
    assert router is None and graph.connect[0] == f"tcp/127.0.0.1:{taken}"
    assert why.startswith(f"the embedded router could not listen on tcp/127.0.0.1:{taken}")
