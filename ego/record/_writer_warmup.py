"""Imported once by the recorders' forkserver (see rerun_recorder._writer_context).

Rerun imports much of its blueprint machinery lazily on first use (~0.2 s); doing it here,
in the server process, means every writer forked from it starts warm.
"""

from ego.record.base import Scene, Series
from ego.record.rerun_recorder import _blueprint

_blueprint(Scene(lanes=[]), [Series("x", "plots/x/x", "m")])

# Ctrl-C and SIGTERM sent to the process group are the simulation process's to handle: it
# ends the run and closes the recording. The forkserver hands the handlers it finds after
# this import to every writer it forks, so a writer ignores both from its first instant.
import signal  # noqa: E402

signal.signal(signal.SIGINT, signal.SIG_IGN)
signal.signal(signal.SIGTERM, signal.SIG_IGN)
