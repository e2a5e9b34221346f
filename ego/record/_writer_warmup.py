"""Imported once by the recorders' forkserver (see rerun_recorder._writer_context).

Rerun imports much of its blueprint machinery lazily on first use (~0.2 s); doing it here,
in the server process, means every writer forked from it starts warm.
"""

from ego.record.base import Scene, Series
from ego.record.rerun_recorder import _blueprint

_blueprint(Scene(lanes=[]), [Series("x", "plots/x/x", "m")])
