"""Rerun recordings (.rrd) with an embedded blueprint, written in batches off the loop.

Layout of a recording (entity paths):

* ``world/map`` - the road in network coordinates, mirrored once (static transform) so
  that +y (left of a road heading east) is up on screen; below it ``world/map/lanes``
  (lane edges, static) and ``world/map/vehicles`` (every vehicle as a closed, labelled
  outline, at SUMO's rate);
* ``world/follow`` - a frame translated to the followed vehicle every SUMO step; both road
  views (the close one and the 300 m one) use it as their origin, so the ego stays put on
  screen;
* ``plots/<panel>/.../<series>`` - time series; the series sharing a parent path share a
  plot panel, which holds one unit; a threshold is a series too (a constant);
* ``states/<name>`` - named states (the manoeuvre's phase), a state timeline;
* ``events`` - the event log; ``run`` - the run's parameters.

The embedded blueprint opens the recording at its end (the time panel follows the latest
data): the plots are complete and the road views show the outcome; scrub back from there.

:class:`RerunRecorder` is what the simulation loop talks to. By default it hands every
batch (plain numpy arrays and lists) over a pipe to a writer process that owns the Rerun
stream, so building Arrow data and encoding the file run on the other core: a thread
would not help, because the loop holds the GIL nearly all the time (libsumo included).
Each batch leaves the writer as ONE Arrow record batch per timeline - the columnar
layout ``send_columns`` produces, but one call for all series instead of one per series.
The scenario flushes at least every simulated second.
"""

from __future__ import annotations

import errno
import multiprocessing
import os
from collections import OrderedDict
from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path

import numpy as np

from ego.outputs import final_path, partial_path
from ego.processes import main_module_hidden, signals_deferred
from ego.record.base import Scene, Series, box_outlines, lane_edges

# Rerun's file sink logs a failed write (a full disk) on stderr itself; ego reports it in one
# line (OutputError), so Rerun's own log is off unless the user asks for it
os.environ.setdefault("RUST_LOG", "off")
#: recording streams whose file could not be written (see RerunWriter.discard)
_ABANDONED: list = []
#: how long closing a recording may wait for Rerun's file sink (s); longer is a stuck disk
FLUSH_TIMEOUT = 120.0

TIMELINE = "sim_time"
_GREY = (150, 150, 150)
#: series colours in a panel, in declaration order, with the names panel titles use
PALETTE = (
    ("blue", (80, 150, 255)),
    ("orange", (255, 160, 40)),
    ("green", (90, 200, 90)),
    ("pink", (240, 100, 200)),
    ("cyan", (60, 210, 230)),
    ("yellow", (230, 220, 60)),
    ("violet", (160, 110, 255)),
    ("white", (230, 230, 230)),
    ("brown", (180, 120, 70)),
    ("olive", (150, 160, 60)),
    ("grey", (140, 140, 140)),
    ("teal", (40, 160, 140)),
)
THRESHOLD = ("red", (230, 50, 50))  #: colour of constants (thresholds)
#: a panel with more series than this shows Rerun's legend; fewer are named in its title
TITLE_SERIES = 4
_LEVELS = {"INFO", "WARN", "ERROR", "DEBUG", "TRACE", "CRITICAL"}
MAP = "world/map"
VEHICLES = "world/map/vehicles"
FOLLOW = "world/follow"


class RerunRecorder:
    """Writes one ``.rrd`` file per run; ``background=True`` writes from a separate process."""

    def __init__(
        self, path: str | Path, *, application_id: str = "ego", recording_id: str | None = None, background: bool = True
    ) -> None:
        self.path = final_path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._box_t: list[float] = []
        self._box_n: list[int] = []
        self._box_rows: list[tuple] = []
        self._box_labels: list[str] = []
        self._follow: list[tuple[float, float]] = []
        self._open = False
        self._used = False
        self._error: str | None = None
        args = (str(self.path), application_id, recording_id)
        if background:
            ctx = _writer_context()
            data_in, self._conn = ctx.Pipe(duplex=False)  # batches: loop -> writer
            self._replies, reply_out = ctx.Pipe(duplex=False)  # failures: writer -> loop
            _widen_pipe(self._conn)
            self._proc = ctx.Process(
                target=_writer_main, args=(data_in, reply_out, *args), daemon=True, name="ego-rerun-writer"
            )
            with main_module_hidden():
                self._proc.start()
            data_in.close()
            reply_out.close()
            self._writer = None
        else:
            self._conn = self._replies = self._proc = None
            self._writer = RerunWriter(*args)

    # -- what the loop calls ------------------------------------------------------------------
    def begin(self, scene: Scene, series: Sequence[Series], meta: dict) -> None:
        if self._used:
            raise RuntimeError(f"{self.path}: a RerunRecorder records one run; make one per run")
        self._used = self._open = True
        self._send("begin", scene, list(series), meta)

    def write_rows(self, columns: Sequence[str], rows: np.ndarray) -> None:
        if len(rows):
            self._send("rows", tuple(columns), rows)

    def vehicles(self, t: float, ids: Sequence[str], poses: Sequence[tuple], follow: tuple[float, float]) -> None:
        self._box_t.append(t)
        self._box_n.append(len(ids))
        self._box_rows.extend(poses)
        self._box_labels.extend(ids)
        self._follow.append(follow)

    def event(self, t: float, text: str, level: str = "INFO") -> None:
        self._send("event", t, text, level)

    def flush(self) -> None:
        if self._box_t:
            self._send("vehicles", self._box_t, self._box_n, self._box_rows, self._box_labels, self._follow)
            self._box_t, self._box_n, self._box_rows, self._box_labels, self._follow = [], [], [], [], []

    def close(self) -> None:
        """Flush, let the writer finish the file, and report its failure if it had one.
        Ctrl-C and SIGTERM wait until the file is whole (a second Ctrl-C must not leave half
        a recording)."""
        from ego.processes import signals_deferred

        with signals_deferred():
            self._close()

    def _close(self) -> None:
        if not self._open:
            self._shutdown()
            return
        self._open = False
        self.flush()
        if self._writer is not None:
            try:
                self._writer.close()
            except OSError as exc:  # a full disk: reported below as an OutputError
                self._error = _describe(exc)
        else:
            self._send("close")
            if self._error is None:
                try:
                    reply = self._replies.recv()
                    if reply[0] == "error":
                        self._error = reply[1]
                except (EOFError, OSError):
                    self._error = "the writer process died"
        self._shutdown()
        if self._error is not None:
            from ego.outputs import OutputError

            raise OutputError(f"cannot write {self.path}: {self._error}")

    # -- plumbing ------------------------------------------------------------------------------
    def _send(self, kind: str, *payload) -> None:
        """Hand a batch to the writer. The pipe is widened to 1 MiB, so this only copies
        bytes: the writer drains it on the other core while the loop goes on."""
        if self._writer is not None:
            if self._error is None:  # a failed recording stops; the run goes on
                try:
                    self._writer.handle(kind, *payload)
                except Exception as exc:  # noqa: BLE001 - reported by close() as an OutputError
                    self._error = _describe(_write_failure(self._writer._partial, exc))
                    self._writer.discard()
            return
        if self._error is not None:
            return
        try:
            if self._replies.poll():  # the writer only speaks to report a failure
                reply = self._replies.recv()
                self._error = reply[1] if reply[0] == "error" else f"unexpected reply {reply[0]!r}"
                return
            with signals_deferred():  # never half a message in the pipe
                self._conn.send((kind, *payload))
        except (EOFError, OSError) as exc:
            self._error = f"the writer process died ({exc})"

    def _shutdown(self) -> None:
        if self._proc is not None:
            self._conn.close()  # the writer exits on end-of-file if it is still waiting
            self._proc.join(timeout=30)
            if self._proc.is_alive():
                self._proc.kill()
            self._replies.close()
            self._proc = None

    def __del__(self) -> None:
        proc = getattr(self, "_proc", None)
        if proc is not None and getattr(proc, "_popen", None) is not None:  # never started: nothing to end
            try:
                proc.kill()
            except (OSError, ValueError, AttributeError):
                pass


def _widen_pipe(conn) -> None:
    """Grow a pipe's kernel buffer to 1 MiB (Linux; the default is 64 KiB), so a writer that
    is still starting up does not block the simulation."""
    try:
        import fcntl

        fcntl.fcntl(conn.fileno(), getattr(fcntl, "F_SETPIPE_SZ", 1031), 1 << 20)
    except (ImportError, OSError):
        pass


@lru_cache(maxsize=1)
def _writer_context():
    """A forkserver context: writers fork from a clean server process (no libsumo, no
    threads) that has imported Rerun once, so each writer starts in milliseconds."""
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(["ego.record._writer_warmup"])
    return ctx


def _writer_main(batches, replies, path: str, application_id: str, recording_id: str | None) -> None:
    """Entry point of the writer process: apply every batch until ``close``.

    Ctrl-C and SIGTERM sent to the whole process group are the simulation process's to
    handle (it ends the run and closes the recording), so the writer ignores them; if the
    simulation process dies instead, the writer still closes the file with everything it
    received."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    writer = None
    try:
        writer = RerunWriter(path, application_id, recording_id)
        while True:
            kind, *payload = batches.recv()
            if kind == "close":
                writer.close()
                replies.send(("done",))
                return
            writer.handle(kind, *payload)
    except EOFError:  # the simulation process died: keep what arrived, named as partial
        if writer is not None:
            writer.close(finished=False)
        return
    except Exception as exc:  # noqa: BLE001 - reported to the simulation process
        if writer is not None:
            exc = _write_failure(writer._partial, exc)  # the errno, asked before the file goes
        try:  # first: the simulation process stops sending and goes on
            replies.send(("error", _describe(exc)))
        except OSError:
            pass
        if writer is not None:  # no half recording left behind
            writer.discard()
            os._exit(0)  # Python's exit would wait for Rerun's stuck thread: the reply is sent


def _describe(exc: BaseException) -> str:
    """An error as one line: an OSError with its errno name, else type and message."""
    if isinstance(exc, OSError) and exc.errno is not None:
        import errno

        return f"[Errno {exc.errno} {errno.errorcode.get(exc.errno, '?')}] {exc.strerror}"
    return f"{type(exc).__name__}: {exc}"


class RerunWriter:
    """Does the actual Rerun work, synchronously (in the writer process, or in-process).

    The recording is written to ``<path>.<pid>.partial`` and renamed to ``path`` when it is
    closed, so ``path`` only ever holds a whole recording (two runs recording to one path
    leave the last one to finish, never a mix); a writer whose run died leaves the partial
    file, named as such."""

    def __init__(self, path: str, application_id: str = "ego", recording_id: str | None = None) -> None:
        import rerun as rr

        self.path = final_path(path)
        self._partial = partial_path(self.path)
        self._rr = rr
        self._rec = rr.RecordingStream(application_id, recording_id=recording_id)
        self._series: dict[str, Series] = {}
        self._constants: list[Series] = []
        self._states: dict[str, Series] = {}
        self._state_now: dict[str, int] = {}
        self._row_plans: dict[tuple, tuple] = {}
        self._colors: dict[str, tuple[int, int, int]] = {}
        self._open = False

    def handle(self, kind: str, *payload) -> None:
        {"begin": self.begin, "rows": self.rows, "vehicles": self.vehicles, "event": self.event}[kind](*payload)

    def begin(self, scene: Scene, series: Sequence[Series], meta: dict) -> None:
        rr = self._rr
        self._series = {s.column: s for s in series if s.constant is None and not s.states}
        self._constants = [s for s in series if s.constant is not None]
        self._states = {s.column: s for s in series if s.states}
        self._colors = dict(meta.get("colors", {}))
        self._open = True  # from here, close() or discard() ends the file
        blueprint = _blueprint(scene, series)
        _watched(lambda: self._rec.save(self._partial, default_blueprint=blueprint), self._partial)
        rec = self._rec
        rec.log(MAP, rr.Transform3D(scale=[1.0, -1.0, 1.0]), static=True)
        edges = []
        for width, centre in scene.lanes:
            left, right = lane_edges(width, centre)
            edges.extend([left, right])
        rec.log(f"{MAP}/lanes", rr.LineStrips2D(edges, colors=[(110, 110, 110)], radii=[0.06]), static=True)
        for panel in _panels(series).values():
            for s, (_, color) in zip(panel, _colors(panel)):
                name = s.label or s.column
                if s.constant is not None:  # its value when hovered
                    name = f"{name} {s.constant:g} {s.unit}".rstrip()
                rec.log(s.path, rr.SeriesLines(names=[name], colors=[color]), static=True)
        summary = "\n".join(f"{k}: {v}" for k, v in meta.items() if k != "colors")
        rec.log("run", rr.TextDocument(summary, media_type="text/plain"), static=True)

    def rows(self, columns: tuple[str, ...], rows: np.ndarray) -> None:
        """Every mapped column of ``rows`` as a time series, in one record batch."""
        import pyarrow as pa

        plan = self._row_plans.get(columns)
        if plan is None:  # which columns go where, and the schema: built once
            picked = [(j, self._series[name]) for j, name in enumerate(columns) if name in self._series]
            fields = [_index_field()] + [
                _component_field(s.path, "Scalars", "scalars", "Scalar", pa.list_(pa.float64()))
                for s in [s for _, s in picked] + self._constants
            ]
            states = [(columns.index(name), s) for name, s in self._states.items() if name in columns]
            plan = self._row_plans[columns] = ([j for j, _ in picked], pa.schema(fields), states)
        index, schema, states = plan
        if states:
            self._state_changes(rows, states)
        if len(schema) == 1:
            return
        offsets = pa.array(np.arange(len(rows) + 1, dtype=np.int32))
        arrays = [_durations(rows[:, 0])]
        for values in [rows[:, j] for j in index] + [np.full(len(rows), s.constant) for s in self._constants]:
            arrays.append(pa.ListArray.from_arrays(offsets, pa.array(values, type=pa.float64())))
        self._rr.send_record_batch(pa.RecordBatch.from_arrays(arrays, schema=schema), recording=self._rec)

    def _state_changes(self, rows: np.ndarray, states: list[tuple[int, Series]]) -> None:
        """Each state column as named state changes: only the rows where it changes."""
        rr = self._rr
        for j, s in states:
            values = rows[:, j].astype(np.int64)
            before = np.concatenate([[self._state_now.get(s.column, -1)], values[:-1]])
            at = np.flatnonzero(values != before)
            if not len(at):
                continue
            self._state_now[s.column] = int(values[-1])
            names = [s.states[v] if 0 <= v < len(s.states) else str(v) for v in values[at]]
            rr.send_columns(
                s.path,
                indexes=[rr.TimeColumn(TIMELINE, duration=rows[at, 0])],
                columns=rr.StateChange.columns(state=names),
                recording=self._rec,
            )

    def vehicles(self, times, counts, poses, labels, follow_points) -> None:
        """Vehicle outlines and the follow frame as one record batch."""
        import pyarrow as pa

        from ego.models.geometry import sumo_poses_to_boxes

        outlines = box_outlines(sumo_poses_to_boxes(poses)).astype(np.float32)
        counts = np.asarray(counts, dtype=np.int32)
        row_offsets = pa.array(np.concatenate([[0], np.cumsum(counts)]).astype(np.int32))
        label_col = pa.ListArray.from_arrays(row_offsets, pa.array(labels, type=pa.string()))
        rgb = np.array([self._colors.get(v, _GREY) for v in labels], dtype=np.uint32).reshape(-1, 3)
        packed = (rgb[:, 0] << 24) | (rgb[:, 1] << 16) | (rgb[:, 2] << 8) | 0xFF
        colors = pa.ListArray.from_arrays(row_offsets, pa.array(packed, type=pa.uint32()))
        follow = np.zeros((len(follow_points), 3), dtype=np.float32)
        follow[:, :2] = follow_points
        follow[:, 1] *= -1.0  # the map is mirrored
        one_each = pa.array(np.arange(len(follow) + 1, dtype=np.int32))
        fields = [
            _index_field(),
            _component_field(VEHICLES, "LineStrips2D", "strips", "LineStrip2D", _strips_type()),
            _component_field(VEHICLES, "LineStrips2D", "labels", "Text", label_col.type),
            _component_field(VEHICLES, "LineStrips2D", "colors", "Color", colors.type),
            _component_field(FOLLOW, "Transform3D", "translation", "Translation3D", _vec3_list_type()),
        ]
        arrays = [
            _durations(np.asarray(times)),
            _strips(outlines, row_offsets),
            label_col,
            colors,
            pa.ListArray.from_arrays(
                one_each,
                pa.FixedSizeListArray.from_arrays(
                    pa.array(follow.reshape(-1), type=pa.float32()), type=_vec3_list_type().value_type
                ),
                type=_vec3_list_type(),
            ),
        ]
        self._rr.send_record_batch(pa.RecordBatch.from_arrays(arrays, schema=pa.schema(fields)), recording=self._rec)

    def event(self, t: float, text: str, level: str = "INFO") -> None:
        self._rec.set_time(TIMELINE, duration=t)
        self._rec.log("events", self._rr.TextLog(text, level=level if level in _LEVELS else "INFO"))

    def close(self, finished: bool = True) -> None:
        """End the file; put it in place unless its run did not finish (``finished=False``:
        the simulation process died, the file keeps its partial name). A file the sink
        could not write whole (a full disk) is removed and an OSError raised: a final name
        only ever holds a whole recording."""
        if self._open:
            self._open = False
            try:
                _flush(self._rec, self._partial)
                self._rec.disconnect()
                if finished:
                    _check_written(self._partial)
                    os.replace(self._partial, self.path)
            except Exception as exc:  # noqa: BLE001 - no half recording under any name
                failure = _write_failure(self._partial, exc)  # asked before the file goes
                self.discard()
                raise failure from None

    def discard(self) -> None:
        """Drop the unfinished file (a write failed): its name first, so nothing is left even
        if Rerun's sink then takes its time to stop."""
        self._open = False
        try:
            self._partial.unlink(missing_ok=True)
        except OSError:
            pass
        # Rerun's sink may wait for ever on a writer thread a full disk stopped: give it a
        # few seconds in a thread of its own, then leave it
        import threading

        def disconnect() -> None:
            try:
                self._rec.disconnect()
            except Exception:  # noqa: BLE001 - the file is going anyway
                pass

        thread = threading.Thread(target=disconnect, name="ego-rerun-discard", daemon=True)
        thread.start()
        thread.join(timeout=5.0)
        # dropping the stream would join its forwarding thread, which Rerun leaves waiting for
        # the dead file writer: the stream is kept for the life of the process instead
        _ABANDONED.append(self._rec)


def _flush(rec, partial: Path) -> None:
    """``rec.flush()``, watched (:func:`_watched`)."""
    _watched(lambda: rec.flush(timeout_sec=FLUSH_TIMEOUT), partial)


def _watched(call, partial: Path) -> None:
    """``call()`` (a Rerun call that writes ``partial``), watched: when the file's
    filesystem is full and the file has stopped growing for a second, Rerun's file writer
    has died (its save and flush may then wait for ever instead of failing): OSError
    ENOSPC, and the call is left to its thread."""
    import threading
    import time

    failure: list[BaseException] = []

    def work() -> None:
        try:
            call()
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            failure.append(exc)

    thread = threading.Thread(target=work, name="ego-rerun-flush", daemon=True)
    thread.start()
    size, still = -1, time.monotonic()
    while thread.is_alive():
        thread.join(timeout=0.1)
        try:
            now = os.path.getsize(partial)
            full = os.statvfs(partial.parent).f_bavail == 0
        except OSError:
            continue
        if now != size:
            size, still = now, time.monotonic()
        elif full and time.monotonic() - still > 1.0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(partial))
    if failure:
        raise failure[0]


def _check_written(partial: Path) -> None:
    """Rerun's file sink reports a failed write only in its log; an empty or missing file is
    one too."""
    try:
        size = os.path.getsize(partial)
    except OSError as exc:
        raise exc
    if size == 0:
        raise OSError(errno.EIO, "the recording is empty", str(partial))


def _write_failure(partial: Path, exc: BaseException) -> OSError:
    """``exc`` (Rerun's ``RuntimeError: File-writer thread shut down prematurely`` says no
    more) as an OSError with the errno the filesystem explains it by."""
    if isinstance(exc, OSError):
        return exc
    try:
        vfs = os.statvfs(partial.parent)
        if vfs.f_bavail == 0:
            return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(partial))
    except OSError:
        pass
    return OSError(errno.EIO, f"the recording's writer failed ({type(exc).__name__}: {exc})", str(partial))


def _panels(series: Sequence[Series]) -> OrderedDict[str, list[Series]]:
    """Plot panel path -> its series, in declaration order (named states are not plots)."""
    panels: OrderedDict[str, list[Series]] = OrderedDict()
    for s in series:
        if not s.states:
            panels.setdefault(s.panel, []).append(s)
    return panels


def _colors(members: Sequence[Series]) -> list[tuple[str, tuple[int, int, int]]]:
    """(name, RGB) of each series of a panel: the palette in turn, thresholds in red."""
    out, k = [], 0
    for s in members:
        if s.constant is not None:
            out.append(THRESHOLD)
        else:
            out.append(PALETTE[k % len(PALETTE)])
            k += 1
    return out


def panel_title(panel: str, members: Sequence[Series]) -> str:
    """A plot panel's title: its name (``plots/<name>/...``), the unit, and which colour is
    which series (so no legend has to cover the data). A lone series is named only when the
    panel's name does not say it already (it is not "ego" nor the panel's own name)."""
    unit = f" [{members[0].unit}]" if members[0].unit else ""
    name = panel.split("/")[1]
    parts = name.split("_")
    if all(len(p) >= 3 for p in parts):  # words: "lateral_error" reads "lateral error"
        name = " ".join(parts)  # symbols ("a_x", "e_d") stay as written
    if len(members) == 1:
        s = members[0]
        entity = s.path.rpartition("/")[2]
        return f"{name}{unit}" if entity in ("ego", panel.split("/")[1]) else f"{name}{unit}: {s.label or s.column}"
    lines = [s for s in members if s.constant is None]
    if len(lines) > TITLE_SERIES:
        return f"{name}{unit}"
    names = [f"{s.label or s.column} {c}" for s, (c, _) in zip(lines, PALETTE)]
    limits = [s.label for s in members if s.constant is not None]
    if limits:  # thresholds share one colour
        names.append(f"{', '.join(limits)} {THRESHOLD[0]}")
    return f"{name}{unit}: {', '.join(names)}"


def _blueprint(scene: Scene, series: Sequence[Series]):
    """The layout: the 300 m around the ego across the top; below, the close view, the
    manoeuvre's states, the events and the run's parameters on the left, the plots on the
    right."""
    import rerun as rr
    import rerun.blueprint as rrb

    plots = []
    for panel, members in _panels(series).items():
        units = {s.unit for s in members}
        if len(units) > 1:  # a declaration error: say which
            raise ValueError(f"panel {panel} mixes units: {', '.join(sorted(units))}")
        axis = rrb.ScalarAxis(range=(0.0, 10.0)) if panel.split("/")[1] == "ttc" else None
        legend = rrb.PlotLegend(visible=len(members) > TITLE_SERIES, corner="RightTop")
        plots.append(
            rrb.TimeSeriesView(origin=panel, name=panel_title(panel, members), axis_y=axis, plot_legend=legend)
        )

    def road(view, name, **kwargs):
        x0, x1, y0, y1 = view  # the map is mirrored: +y (left) is up on screen
        return rrb.Spatial2DView(
            origin=FOLLOW,
            contents="world/**",
            name=name,
            visual_bounds=rrb.VisualBounds2D(x_range=(x0, x1), y_range=(-y1, -y0)),
            **kwargs,
        )

    a0, a1 = scene.around_view[:2]
    # no labels at this scale: they would lie on top of each other (colours tell ego and lead)
    around = road(
        scene.around_view,
        f"{a1 - a0:.0f} m around {scene.followed} ({-a0:.0f} m behind, {a1:.0f} m ahead)",
        overrides={VEHICLES: rr.LineStrips2D.from_fields(show_labels=False)},
    )
    close = road(scene.follow_view, f"following {scene.followed}")
    left = [close]
    shares = [3]
    if any(s.states for s in series):
        left.append(rrb.StateTimelineView(origin="states", name="manoeuvre"))
        shares.append(1)
    events = rrb.TextLogView(
        origin="events",
        name="events",
        columns=rrb.TextLogColumns(timeline_columns=[TIMELINE], text_log_columns=["loglevel", "body"]),
    )
    left.append(rrb.Tabs(events, rrb.TextDocumentView(origin="run", name="run")))
    shares.append(3)
    below = rrb.Horizontal(
        rrb.Vertical(*left, row_shares=shares), rrb.Grid(*plots, grid_columns=3), column_shares=[1, 3]
    )
    return rrb.Blueprint(
        rrb.Vertical(around, below, row_shares=[1, 6]),
        rrb.TimePanel(timeline=TIMELINE, play_state="following", state="collapsed"),
        collapse_panels=True,
    )


# -- Arrow plumbing (the layout Rerun's own send_columns produces) ------------------------


def _pa():
    import pyarrow as pa

    return pa


def _index_field():
    pa = _pa()
    return pa.field(
        TIMELINE, pa.duration("ns"), metadata={b"rerun:kind": b"index", b"rerun:index_name": TIMELINE.encode()}
    )


def _durations(seconds: np.ndarray):
    pa = _pa()
    return pa.array(np.round(np.asarray(seconds) * 1e9).astype(np.int64), type=pa.duration("ns"))


def _component_field(entity: str, archetype: str, component: str, component_type: str, arrow_type):
    pa = _pa()
    return pa.field(
        f"/{entity}:{archetype}:{component}",
        arrow_type,
        metadata={
            b"rerun:kind": b"data",
            b"rerun:entity_path": ("/" + entity).encode(),
            b"rerun:archetype": f"rerun.archetypes.{archetype}".encode(),
            b"rerun:component": f"{archetype}:{component}".encode(),
            b"rerun:component_type": f"rerun.components.{component_type}".encode(),
        },
    )


@lru_cache(maxsize=1)
def _strips_type():
    """Arrow type of a LineStrip2D column: per row, a list of strips of 2-D float32 points."""
    pa = _pa()
    point = pa.list_(pa.field("item", pa.float32(), nullable=False), 2)
    strip = pa.list_(pa.field("item", point, nullable=False))
    return pa.list_(pa.field("item", strip))


@lru_cache(maxsize=1)
def _vec3_list_type():
    """Arrow type of a Translation3D column: per row, a list of 3-D float32 vectors."""
    pa = _pa()
    return pa.list_(pa.list_(pa.field("item", pa.float32(), nullable=False), 3))


def _strips(outlines: np.ndarray, row_offsets):
    """(n, k, 2) closed outlines grouped per time row by ``row_offsets``."""
    pa = _pa()
    rows_t = _strips_type()
    n, k, _ = outlines.shape
    strip_t = rows_t.value_type
    point_t = strip_t.value_type
    points = pa.FixedSizeListArray.from_arrays(pa.array(outlines.reshape(-1), type=pa.float32()), type=point_t)
    strips = pa.ListArray.from_arrays(pa.array(np.arange(0, n * k + 1, k, dtype=np.int32)), points, type=strip_t)
    return pa.ListArray.from_arrays(row_offsets, strips, type=rows_t)
