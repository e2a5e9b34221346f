"""Tune report 003's cascade PID by differential evolution, a generation at a time.

    ego tune lane-centering [--quick] [--workers N] [--seed N] [--out PATH]

The report's set-up: scipy's differential evolution, population 15 (x 12 parameters = 180
members), at most 100 generations, the 12 PID gains, and the cost

    max|e| + 0.5 mean|e| + 0.1 std|e| + 10 max(0, max|e| - 0.5)

of the lateral error over report 003's whole road at 8 m/s (dt 0.01 s, the lateral-error
model, curvature feed-forward and the report's adaptive gain).

Every generation is ONE vectorised numpy simulation of all its members over the road
(:func:`simulate_batch`: arrays of members, one time loop), not a loop over members. Two
exact shortcuts: the model is integrated by its zero-order-hold matrices, and the first
straight is skipped - from rest on a straight every state stays exactly zero - and counted
as zeros. ``--workers N`` splits each generation over N processes. :func:`simulate_single`
is the plain one-run simulation with the scenario's controller; tests hold the two equal.
"""

from __future__ import annotations

import json
import math
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ego.analytic_road import report003_road
from ego.checks import MAX_JOBS, check_count, check_number, check_seed, finite_number
from ego.control.cascade import GAIN_NAMES, REPORT_GAINS, TUNED_PRESET, Cascade
from ego.models.lateral_error import LateralError, LateralErrorParams
from ego.outputs import write_text
from ego.params import ConfigError, did_you_mean, shown

MAX_ERROR = 0.5  #: the report's goal (m)
DIVERGED = 1e3  #: |e| (m) beyond which a member is lost (its cost is then >= 1e4)


@dataclass(frozen=True)
class Setup:
    """One simulated drive: report 003's road, speed, step and the cascade's numerics."""

    speed: float = 8.0  #: m/s (report 003)
    dt: float = 0.01  #: s (report 003)
    integral_limit: float = 1.0
    alpha: float = 0.2
    adaptive: bool = True
    feedforward: bool = True
    steer_limit: float = math.radians(25.0)
    steer_rate: float = math.radians(30.0)  #: rad/s
    offset: float = 0.0  #: initial lateral error (m, + left); the drive starts from rest otherwise
    duration: float = 0.0  #: s of the road from its start; 0: the whole road

    def curvature(self) -> np.ndarray:
        """The lane's curvature under the car at every step of the drive (the reference
        point advances at the speed)."""
        road = report003_road()
        length = road.length if self.duration <= 0 else min(road.length, self.speed * self.duration)
        n = int(math.ceil(length / (self.speed * self.dt)))
        return road.curvature(self.speed * self.dt * np.arange(n))


def _plant(setup: Setup) -> list[np.ndarray]:
    """The model's zero-order-hold columns (see :meth:`LateralError.columns`)."""
    return LateralError(LateralErrorParams(), setup.speed).columns(setup.dt)


def _law(gains, setup: Setup) -> Cascade:
    return Cascade(
        gains,
        setup.dt,
        setup.integral_limit,
        setup.alpha,
        setup.adaptive,
        setup.feedforward,
        setup.steer_limit,
        setup.steer_rate,
    )


def simulate_single(gains, setup: Setup = Setup(), kappa: np.ndarray | None = None) -> np.ndarray:
    """The lateral error at every step of one drive, with the scenario's controller
    (:class:`ego.control.cascade.Cascade`) and a plain loop."""
    kappa = setup.curvature() if kappa is None else kappa
    step = LateralError(LateralErrorParams(), setup.speed).stepper(setup.dt)
    law = _law(gains, setup)
    x = (setup.offset, 0.0, 0.0, 0.0)
    out = np.empty(len(kappa))
    v = setup.speed
    for k, kap in enumerate(kappa.tolist()):
        out[k] = x[0]
        delta = law.step(x[0], x[1], x[2], x[3], kap, v)
        x = step(x, delta, kap)
    return out


def simulate_batch(gains: np.ndarray, setup: Setup = Setup(), kappa: np.ndarray | None = None, record: bool = False):
    """All members at once on one drive: ``gains`` (N, 12). Returns (max|e|, mean|e|,
    std|e|) arrays of shape (N,), and with ``record`` also the errors (N, steps)."""
    kappa = setup.curvature() if kappa is None else kappa
    stats, recs = simulate_drives(gains, [setup], [kappa], record=record)
    return (stats[0], recs[0]) if record else stats[0]


def simulate_drives(
    gains: np.ndarray, setups: list[Setup], kappas: list[np.ndarray] | None = None, record: bool = False
):
    """All members on several drives (speeds) in ONE time loop: ``gains`` (N, 12).

    Returns a list of (max|e|, mean|e|, std|e|) per drive, and the errors (N, steps) per
    drive when ``record`` (else Nones). The columns are drive-major blocks of the N members;
    every operation acts on all of them at once (arrays of B N, preallocated outputs, the
    four loops written out) - numpy's per-call cost, not the number of columns, sets the
    pace. Each drive starts one step before its curvature does (from rest on a straight
    nothing moves; those steps count as zeros) and drives that have ended idle along."""
    G = np.asarray(gains, dtype=float)
    if G.ndim != 2 or G.shape[1] != 12:
        raise ValueError(f"gains must be (members, 12), got {G.shape}")
    setups, kappas = _check_drives(setups, kappas)
    base = setups[0]
    N0 = G.shape[0]
    if N0 == 1:  # einsum's single-column path sums differently: pad to two
        G = np.vstack([G, G])
    N, B = G.shape[0], len(setups)
    C = N * B
    blocks = [slice(b * N, (b + 1) * N) for b in range(B)]
    law = _law(np.zeros(12), base)  # the numerics' constants, computed as the law does
    dt, alpha = base.dt, base.alpha
    # per loop a (3, C) block [err, integral/dt, filtered derivative/(alpha/dt)] and the
    # matching gains [kp, ki dt, kd alpha/dt]: u = (K * S) summed over the rows, in order
    K = _gain_rows(G, B, dt, alpha)
    S = np.zeros((4, 3, C))
    prev = np.zeros((4, C))
    T3 = np.empty((3, C))

    def full(value):
        return np.full(C, float(value))

    beta, ilim, nilim = full(law.beta), full(law.ilim), full(-law.ilim)
    rate, slim, nslim = full(law.rate), full(law.lim), full(-law.lim)
    ffs = [law.L + law.K * st.speed * st.speed for st in setups]
    lo_e, hi_e, c08, c15 = full(0.1), full(0.5), full(0.8), full(1.5)
    # the plant: x' = P [e, psi, vy, r, delta, kappa], each column with its drive's P, as
    # one einsum whose per-element sums run in column order like the single run's
    # (checked by the tests; einsum sums differently for a single column, hence two)
    Ps = [np.column_stack(_plant(st)) for st in setups]
    P3 = np.concatenate([np.repeat(P[:, :, None], N, axis=2) for P in Ps], axis=2)
    Z, Zn = np.zeros((6, C)), np.zeros((6, C))  # [x; delta; kappa], now and next
    for blk, st in zip(blocks, setups):
        Z[0, blk] = st.offset

    ns, k0s, J, kap_j = _first_steps(kappas, setups)
    starts_at_zero = [blk for blk, k0 in zip(blocks, k0s) if k0 == 0]
    refs = np.empty((4, C))  # psi_ref, vy_ref, r_ref, delta_fb
    t = np.empty(C)
    g = np.empty(C)
    b = np.empty(C, dtype=bool)
    # the errors from each drive's first simulated step, a row per step (one cheap copy each)
    recs = [np.empty((n - k0, N)) for n, k0 in zip(ns, k0s)]
    mul, sub, add, neg, einsum = np.multiply, np.subtract, np.add, np.negative, np.einsum
    vmin, vmax, reduce = np.minimum, np.maximum, np.add.reduce
    less, greater, copyto, absolute = np.less, np.greater, np.copyto, np.abs
    (S0, S1, S2, S3) = S
    (E0, I0, D0), (E1, I1, D1), (E2, I2, D2), (E3, I3, D3) = S
    R0, R1, R2, R3 = prev  # beta D - err of the last step: D = that + err next step
    Eall, Dall = S[:, 0], S[:, 2]
    K0, K1, K2, K3 = K
    U0, U1, U2, U3 = refs
    adaptive, feedforward = base.adaptive, base.feedforward

    def views(buf, nxt):
        """Per-step views of a buffer and the other one (they swap every step)."""
        return (
            buf,
            nxt[:4],
            tuple(buf),
            nxt[4],
            buf[4],
            [
                (rec, k0, n, buf[0, blk], buf[5, blk], U3[blk], kaps, ff)
                for blk, rec, k0, n, kaps, ff in zip(blocks, recs, k0s, ns, kap_j, ffs)
            ],
        )

    va, vb = views(Z, Zn), views(Zn, Z)
    for j in range(J):
        Zc, Zx4, (e, psi, vy, r, delta_prev, _), delta_next, delta_now, dv = va if j % 2 == 0 else vb
        # loop 1: e -> psi_err_ref (with the adaptive gain)
        neg(e, out=E0)
        I0 += E0
        vmin(I0, ilim, out=I0)
        vmax(I0, nilim, out=I0)
        add(R0, E0, out=D0)
        if j == 0:
            for blk in starts_at_zero:  # no derivative on a drive's first step
                D0[blk] = 0.0
        mul(K0, S0, out=T3)
        reduce(T3, axis=0, out=U0)
        if adaptive:
            absolute(e, out=t)
            g.fill(1.0)
            less(t, lo_e, out=b)
            copyto(g, c08, where=b)
            greater(t, hi_e, out=b)
            copyto(g, c15, where=b)
            U0 *= g
        # loop 2: psi_err -> vy_ref
        sub(U0, psi, out=E1)
        I1 += E1
        vmin(I1, ilim, out=I1)
        vmax(I1, nilim, out=I1)
        add(R1, E1, out=D1)
        if j == 0:
            for blk in starts_at_zero:
                D1[blk] = 0.0
        mul(K1, S1, out=T3)
        reduce(T3, axis=0, out=U1)
        # loop 3: vy -> r_ref
        sub(U1, vy, out=E2)
        I2 += E2
        vmin(I2, ilim, out=I2)
        vmax(I2, nilim, out=I2)
        add(R2, E2, out=D2)
        if j == 0:
            for blk in starts_at_zero:
                D2[blk] = 0.0
        mul(K2, S2, out=T3)
        reduce(T3, axis=0, out=U2)
        # loop 4: r -> delta
        sub(U2, r, out=E3)
        I3 += E3
        vmin(I3, ilim, out=I3)
        vmax(I3, nilim, out=I3)
        add(R3, E3, out=D3)
        if j == 0:
            for blk in starts_at_zero:
                D3[blk] = 0.0
        mul(K3, S3, out=T3)
        reduce(T3, axis=0, out=U3)
        # record e, feed-forward, then the rate and magnitude limits; the steer lands in Z
        for rec, k0, n, e_blk, kap_blk, u_blk, kaps, ff in dv:
            if k0 + j < n:
                rec[j] = e_blk
            kap = kaps[j]
            if j < 2 or kap != kaps[j - 2]:  # (this buffer's row holds the value of j - 2)
                kap_blk.fill(kap)
            if feedforward and kap != 0.0:  # (adding 0 changes nothing)
                u_blk += kap * ff
        add(delta_prev, rate, out=t)
        vmin(U3, t, out=U3)
        sub(delta_prev, rate, out=t)
        vmax(U3, t, out=U3)
        vmin(U3, slim, out=U3)
        vmax(U3, nslim, out=delta_now)
        einsum("ijn,jn->in", P3, Zc, out=Zx4)
        delta_next[:] = delta_now
        # every loop's beta D - err, for the next step's derivative
        mul(beta, Dall, out=prev)
        prev -= Eall

    return _error_stats(recs, ns, k0s, N0, record)


def _check_drives(setups, kappas) -> tuple[list[Setup], list[np.ndarray]]:
    """The drives and their curvatures (each drive's own when ``kappas`` is None); a
    ValueError unless they differ in speed, initial offset and duration only."""
    setups = list(setups)
    kappas = [
        np.asarray(s.curvature() if kappas is None else k, dtype=float)
        for s, k in zip(setups, kappas or [None] * len(setups))
    ]
    base = setups[0]
    drive_only = {"speed": 0, "offset": 0, "duration": 0}
    for st in setups[1:]:
        if {**asdict(st), **drive_only} != {**asdict(base), **drive_only}:
            raise ValueError("the drives may differ in speed, initial offset and duration only")
    return setups, kappas


def _gain_rows(G: np.ndarray, B: int, dt: float, alpha: float) -> np.ndarray:
    """Per loop the gains [kp, ki dt, kd alpha/dt] of each column (B drive blocks of the
    members): (4, 3, B N)."""
    K = np.empty((4, 3, G.shape[0] * B))
    for i in range(4):
        K[i, 0] = np.tile(G[:, 3 * i], B)
        K[i, 1] = np.tile([x * dt for x in G[:, 3 * i + 1].tolist()], B)
        K[i, 2] = np.tile([x * (alpha / dt) for x in G[:, 3 * i + 2].tolist()], B)
    return K


def _first_steps(kappas: list[np.ndarray], setups: list[Setup]) -> tuple[list[int], list[int], int, list[list]]:
    """Each drive's steps, its first simulated step (one before its curvature starts, or 0
    when it starts off the line), the loop's length and each drive's curvature along the
    loop (zero once it has ended)."""
    ns = [len(k) for k in kappas]
    k0s = []
    for k, st in zip(kappas, setups):
        nz = np.flatnonzero(k)
        if st.offset != 0.0:  # something moves from the start
            k0s.append(0)
        else:
            k0s.append(max(int(nz[0]) - 1, 0) if nz.size else len(k))
    J = max(n - k0 for n, k0 in zip(ns, k0s))
    kap_j = [np.concatenate([k[k0:], np.zeros(J - (n - k0))]).tolist() for k, n, k0 in zip(kappas, ns, k0s)]
    return ns, k0s, J, kap_j


def _error_stats(recs: list[np.ndarray], ns: list[int], k0s: list[int], N0: int, record: bool):
    """Per drive (max|e|, mean|e|, std|e|) of the first ``N0`` members over all its steps
    (the skipped ones zeros), and the errors (N0, steps) when ``record`` (else Nones)."""
    stats, out_recs = [], []
    for rec, n, k0 in zip(recs, ns, k0s):
        if record:
            full_rec = np.zeros((N0, n))
            full_rec[:, k0:] = rec[:, :N0].T
            out_recs.append(full_rec)
        else:
            out_recs.append(None)
        a = np.abs(rec[:, :N0], out=rec[:, :N0])  # the skipped steps are zeros: they add nothing
        mean = a.sum(axis=0) / n
        sq = np.einsum("kn,kn->n", a, a)
        std = np.sqrt(np.maximum(sq / n - mean * mean, 0.0))
        stats.append((a.max(axis=0) if len(a) else np.zeros(N0), mean, std))
    return stats, out_recs


def cost(max_abs, mean_abs, std_abs):
    """The report's cost (works on arrays); non-finite or lost runs cost >= 1e4."""
    c = max_abs + 0.5 * mean_abs + 0.1 * std_abs + 10.0 * np.maximum(0.0, max_abs - MAX_ERROR)
    return np.where(np.isfinite(c) & (max_abs < DIVERGED), c, 1e4 + np.nan_to_num(max_abs, posinf=1e6))


# --- differential evolution -------------------------------------------------------------------

#: the gains' search box (the report's result lies inside it)
BOUNDS = [(0.0, 2.0)] * 12


#: the speeds (m/s) and largest initial offset (m) of a drive; the longest SUMO cost run (s)
DRIVE_SPEEDS, MAX_OFFSET, MAX_DURATION = (2.0, 30.0), 1.5, 3600.0


def check_drives(drives, what: str = "drives", text: str | None = None) -> None:
    """(speed, offset) pairs within ``DRIVE_SPEEDS`` and ``MAX_OFFSET``, or ConfigError
    quoting ``text`` (what the user wrote) or the drives."""
    lo, hi = DRIVE_SPEEDS
    pairs = (
        isinstance(drives, (tuple, list))
        and len(drives) > 0
        and all(isinstance(d, (tuple, list)) and len(d) == 2 and all(finite_number(x) for x in d) for d in drives)
    )
    if not pairs or any(not lo <= v <= hi or abs(o) > MAX_OFFSET for v, o in drives):
        raise ConfigError(
            f"bad value for {what}: {shown(text if text is not None else drives)} (expected "
            f"speeds from {lo:g} to {hi:g} m/s and offsets within {MAX_OFFSET:g} m)"
        )


@dataclass(frozen=True)
class TuneSpec:
    """Differential evolution as report 003 ran it - population 15, 100 generations, its
    cost - on the cost summed over ``drives``: (speed m/s, initial offset m) each over the
    whole road. The report's drive is (8, 0); (25, 1) adds its speed variant starting 1 m
    off the lane centre, so the gains must also recover from a disturbance."""

    popsize: int = 15  #: x 12 parameters = 180 members
    maxiter: int = 100
    seed: int = 0
    workers: int = 1  #: processes sharing each generation
    #: scipy stops when the population's costs agree within tol x their mean; the drive
    #: starting off-centre adds a cost no gains avoid, which would stop it early: 0 runs
    #: all ``maxiter`` generations
    tol: float = 0.0
    drives: tuple[tuple[float, float], ...] = ((8.0, 0.0), (25.0, 1.0))
    #: what a member's cost is: "model" simulates the lateral-error model for the whole
    #: population at once in numpy (the default, the report's setting); "sumo" runs the
    #: lane-centering scenario in SUMO on the dynamic bicycle for each member and drive,
    #: through ``engine`` (process or ray, ``address`` to join a cluster)
    cost: str = "model"
    engine: str = "process"
    address: str | None = None
    duration: float | None = None  #: cost=sumo: simulated time of each run (s; None: the road)

    def __post_init__(self) -> None:
        """The same checks as ``ego tune``'s options, from Python: ConfigError."""
        from ego.parallel.executor import ENGINES

        check_count(self.popsize, "popsize", 1, 1000)
        check_count(self.maxiter, "maxiter", 1, 100_000)
        check_seed(self.seed, "seed")
        check_count(self.workers, "workers", 1, MAX_JOBS)
        check_number(self.tol, "tol", 0.0, 1.0, "")
        check_drives(self.drives)
        for name, allowed in (("cost", ("model", "sumo")), ("engine", ENGINES)):
            if getattr(self, name) not in allowed:
                raise ConfigError(
                    f"bad value for {name}: {getattr(self, name)!r} (expected one of "
                    f"{', '.join(allowed)}){did_you_mean(getattr(self, name), allowed)}"
                )
        if self.address is not None and not isinstance(self.address, str):
            raise ConfigError(f"bad value for address: {self.address!r} (expected text, e.g. auto)")
        check_number(self.duration, "duration", 1.0, MAX_DURATION, "s")

    @classmethod
    def quick(cls, seed: int = 0, workers: int = 1) -> TuneSpec:
        """A few small generations: for tests and a first look (~5 s)."""
        return cls(popsize=4, maxiter=4, seed=seed, workers=workers)


_DRIVES: dict = {}


def drives(spec: tuple[tuple[float, float], ...]) -> tuple[list[Setup], list[np.ndarray]]:
    """The setups and curvature schedules of ``spec``'s (speed, offset) drives (cached)."""
    if spec not in _DRIVES:
        setups = [Setup(speed=v, offset=o) for v, o in spec]
        _DRIVES[spec] = (setups, [st.curvature() for st in setups])
    return _DRIVES[spec]


def drive_name(speed: float, offset: float) -> str:
    return f"{speed:g} m/s" + (f", {offset:+g} m off" if offset else "")


def total_cost(gains: np.ndarray, spec: tuple[tuple[float, float], ...]) -> np.ndarray:
    """The report's cost of each row of ``gains``, summed over the drives."""
    setups, kappas = drives(spec)
    stats, _ = simulate_drives(gains, setups, kappas)
    return sum(cost(*st) for st in stats)


class _Objective:
    """scipy's vectorised objective: x (12, members) -> costs, split over the workers."""

    def __init__(self, speeds: tuple[tuple[float, float], ...], workers: int) -> None:
        self.speeds = speeds
        self.workers = workers
        self.pool = None
        self.generations = 0
        self.members = 0
        self.initial_best: float | None = None
        if workers > 1:
            import multiprocessing
            import os

            from ego.processes import exit_with, main_module_hidden

            # the workers die with this process, even mid-generation (a killed ego tune)
            self.pool = ProcessPoolExecutor(
                workers,
                mp_context=multiprocessing.get_context("forkserver"),
                initializer=exit_with,
                initargs=(os.getpid(),),
            )
            with main_module_hidden():  # warm the workers up (each computes the road once)
                list(self.pool.map(total_cost, [np.array([REPORT_GAINS])] * workers, [speeds] * workers))

    def __call__(self, x: np.ndarray) -> np.ndarray:
        members = np.ascontiguousarray(np.asarray(x).T)
        self.generations += 1
        self.members += len(members)
        if self.pool is None or len(members) < 2 * self.workers:
            costs = total_cost(members, self.speeds)
        else:
            chunks = np.array_split(members, self.workers)
            costs = np.concatenate(list(self.pool.map(total_cost, chunks, [self.speeds] * len(chunks))))
        if self.initial_best is None:
            self.initial_best = float(costs.min())
        return costs

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown()


def sumo_cost(task: tuple) -> float:
    """One member on one drive in SUMO: (gains, speed m/s, offset m, duration s or None) ->
    the report's cost of the run's lateral error (a run that does not complete costs 1e4+)."""
    from ego.control.cascade import CascadePID, CascadePIDParams
    from ego.runner import RunSpec, resolve
    from ego.scenarios.base import NOT_FAILED

    gains, speed, offset, duration = task
    overrides = {"speed": speed, "offset": offset, "plant": "dynamic-bicycle"}
    if duration is not None:
        overrides["duration"] = duration
    resolved = resolve(RunSpec("lane-centering", "cascade-pid", 0, overrides))
    cls, config = resolved.scenario_cls, resolved.config
    p = CascadePIDParams(preset="report")
    controller = CascadePID(p, config.dt)
    controller.law = Cascade(
        tuple(gains),
        config.dt,
        p.integral_limit,
        p.alpha,
        p.adaptive,
        p.feedforward,
        math.radians(p.steer_limit),
        math.radians(p.steer_rate),
    )
    result = cls(config, controller, seed=0, controller_name="cascade-pid").run()
    e = np.abs(result.column("d"))
    if result.status not in NOT_FAILED or not e.size:  # ended: a shortened drive
        return float(1e4 + (np.nanmax(e) if e.size else 0.0))
    return float(cost(np.array([e.max()]), np.array([e.mean()]), np.array([e.std()]))[0])


class _SumoObjective:
    """The vectorised objective with each member's cost from SUMO runs on an executor."""

    def __init__(self, spec: TuneSpec) -> None:
        from ego.parallel.executor import make_executor

        self.spec = spec
        self.executor = make_executor(spec.engine, spec.workers, spec.address)
        self.generations = 0
        self.members = 0
        self.initial_best: float | None = None

    def __call__(self, x: np.ndarray) -> np.ndarray:
        members = np.ascontiguousarray(np.asarray(x).T)
        self.generations += 1
        self.members += len(members)
        tasks = [
            (i, (tuple(map(float, g)), v, o, self.spec.duration))
            for i, g in enumerate(members)
            for v, o in self.spec.drives
        ]
        costs = np.zeros(len(members))
        for outcome in self.executor.run(_indexed_sumo_cost, tasks):
            i = outcome.task[0]
            costs[i] += outcome.value if outcome.value is not None else 1e6
        if self.initial_best is None:
            self.initial_best = float(costs.min())
        return costs

    def close(self) -> None:
        self.executor.close()


def _indexed_sumo_cost(task: tuple) -> float:
    return sumo_cost(task[1])


def drive_figures(gain_sets, spec: tuple[tuple[float, float], ...]) -> list[dict]:
    """Cost and lateral-error figures of each set of gains on each drive (one simulation)."""
    setups, kappas = drives(spec)
    stats, _ = simulate_drives(np.array(gain_sets, dtype=float), setups, kappas)
    out = []
    for j in range(len(gain_sets)):
        figures = {}
        for (v, o), (mx, mn, sd) in zip(spec, stats):
            figures[drive_name(v, o)] = {
                "cost": float(cost(mx[j : j + 1], mn[j : j + 1], sd[j : j + 1])[0]),
                "max_abs_lateral_error": float(mx[j]),
                "mean_abs_lateral_error": float(mn[j]),
                "std_abs_lateral_error": float(sd[j]),
            }
        out.append(figures)
    return out


def tune(spec: TuneSpec = TuneSpec(), out: Path | None = TUNED_PRESET, log=print) -> dict:
    """Run the tuning; write the preset (gains and how they were found) to ``out``."""
    from scipy import __version__ as scipy_version
    from scipy.optimize import differential_evolution

    t0 = time.perf_counter()
    speeds = tuple((float(v), float(o)) for v, o in spec.drives)
    objective = _SumoObjective(spec) if spec.cost == "sumo" else _Objective(speeds, spec.workers)
    best = []

    def progress(intermediate_result):
        best.append(float(intermediate_result.fun))
        log(f"generation {len(best):3d}: best cost {best[-1]:.6f} ({time.perf_counter() - t0:6.1f} s)")

    try:
        result = differential_evolution(
            objective,
            BOUNDS,
            popsize=spec.popsize,
            maxiter=spec.maxiter,
            seed=spec.seed,
            tol=spec.tol,
            vectorized=True,
            updating="deferred",
            polish=False,
            callback=progress,
        )
    finally:
        objective.close()
    wall = time.perf_counter() - t0
    gains = [float(g) for g in result.x]
    tuned, report = drive_figures([gains, REPORT_GAINS], speeds)
    preset = {
        "gains": dict(zip(GAIN_NAMES, gains)),
        "cost": float(result.fun),
        "drives": tuned,
        "report_gains": report,
        "initial_population_best_cost": objective.initial_best,
        "best_cost_per_generation": best,
        "generations": int(result.nit),
        "simulated_members": objective.members,
        "members_per_generation": spec.popsize * 12,
        "converged": bool(result.success),
        "message": str(result.message),
        "seconds": round(wall, 2),
        "differential_evolution": {
            **asdict(spec),
            "bounds": BOUNDS,
            "updating": "deferred",
            "polish": False,
            "vectorized": True,
        },
        "setup": {k: v for k, v in asdict(Setup()).items() if k != "speed"},
        "scipy": scipy_version,
    }
    for v, fig in tuned.items():
        log(
            f"  {v}: max |e| {fig['max_abs_lateral_error']:.2e} m, mean {fig['mean_abs_lateral_error']:.2e} m "
            f"(report 003's gains: max |e| {report[v]['max_abs_lateral_error']:.3f} m)"
        )
    log(
        f"best cost {result.fun:.6f} after {result.nit} generations ({objective.members} members "
        f"simulated on each drive) in {wall:.1f} s"
    )
    if out is not None:
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        write_text(out, json.dumps(preset, indent=2) + "\n")
        log(f"wrote {out}")
    return preset
