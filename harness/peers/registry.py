"""The peer methods ``djl-fmu compare`` runs, in table order: the registry.

Each entry names a method and its builder (``build_*(ctx, name)`` in the
method's own module, :mod:`harness.peers.context`).  Adding a peer is its
module with a builder, plus one line here.
"""

from __future__ import annotations

from dataclasses import dataclass

from .context import PeerBuilder, PeerContext, PeerSpec
from .damped_jerk import build_damped_jerk
from .robust_shapers import build_mm_zvd, build_si
from .ruckig_ref import build_time_optimal
from .sato import build_sato
from .shapers import build_shaped
from .trajectory import Motion
from .tv_shaper import build_tv_shaped

__all__ = ["ALL_PEERS", "OPTIONAL_PEERS", "PEERS", "Peer", "REGISTRY", "build"]


@dataclass(frozen=True)
class Peer:
    """A registered peer method.

    Attributes
    ----------
    name : str
        Its row label (``"AL*ZV"``).
    builder : PeerBuilder
        Builds it for a context.
    default : bool
        Run unless the user picks the peers (``--peers``).
    """

    name: str
    builder: PeerBuilder
    default: bool = True


REGISTRY: tuple[Peer, ...] = (
    Peer("time-optimal JL", build_time_optimal),
    Peer("Sato III", build_sato),
    Peer("AL*ZV", build_shaped),
    Peer("AL*ZVD", build_shaped),
    Peer("AL*MZV", build_shaped),
    Peer("AL*EI", build_shaped),
    Peer("JL*ZV", build_shaped),
    Peer("JL*ZVD", build_shaped),
    Peer("JL*EI", build_shaped),
    Peer("JL*SI", build_si),
    Peer("AL*TV-ZV", build_tv_shaped),
    Peer("JL*TV-ZV", build_tv_shaped),
    Peer("damped jerk", build_damped_jerk),
    Peer("JL*MZV", build_shaped, default=False),
    Peer("JL*MM-ZVD", build_mm_zvd, default=False),
)
"""Every peer, in table order."""

PEERS = tuple(p.name for p in REGISTRY if p.default)
"""The peer methods run by default, in table order (after AL, JL, DJL)."""

OPTIONAL_PEERS = tuple(p.name for p in REGISTRY if not p.default)
"""Peers run only when asked for (``peers=`` / ``--peers``)."""

ALL_PEERS = PEERS + OPTIONAL_PEERS
"""Every peer :func:`build` knows."""

_BY_NAME = {p.name: p for p in REGISTRY}


def build(ctx: PeerContext, name: str) -> tuple[Motion, PeerSpec]:
    """Build the peer ``name`` for a context.

    Raises
    ------
    ValueError
        If no peer of that name is registered.
    """
    peer = _BY_NAME.get(name)
    if peer is None:
        raise ValueError(f"unknown peer method {name!r}; choose from {ALL_PEERS}")
    return peer.builder(ctx, name)
