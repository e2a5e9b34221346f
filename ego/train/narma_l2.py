"""Identify report 002's car for NARMA-L2: designed excitation, then f and g in torch.

    ego train narma-l2 [--seed N] [--samples N] [--epochs N] [--out PATH]

Data. The report identified its plant from 100 samples at one operating point (30 km/h,
a_x = 0.3 m/s^2), and its controller failed anywhere else. Here each episode draws an
entry speed in [20, 40] km/h, an axial acceleration in [0, 0.6] m/s^2, a curve (a
90-degree arc, radius log-uniform in [12, 60] m, left or right, between straights) and a
small initial offset, and drives :class:`ego.models.DynamicBicycle` through it with the
lane errors measured exactly as in the scenario (:class:`ego.lane_frame.LanePolyline` on a lane
sampled every degree like ``sumo_nets/curve``). The steer is a stabilising feedback
(curvature feed-forward plus error feedback, so the car stays where a controller keeps
it) plus the excitation: random levels up to +-0.1 rad held for 1-5 samples (a
multi-level pseudo-random signal), so every sample carries information about g.
Every fifth episode is held out (too few episodes: the last fifth of the samples).

Training. f = y + dy_scale * F(x) and g = g_scale * G(x); F and G are 32-32-1 tanh
networks (12 inputs) trained jointly on the one-step-ahead error with Adam, on one CPU thread with
deterministic algorithms and a seeded generator: the same seed gives the same weights.
"""

from __future__ import annotations

import json
import math
import platform
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ego.checks import MAX_SEED
from ego.control.narma import DEFAULT_MODEL, FEATURES
from ego.lane_frame import LanePolyline
from ego.models import DynamicBicycle, DynamicBicycleParams
from ego.outputs import atomic_path, write_text
from ego.params import HALF_PI, ConfigError, Params, param

KMH = 1.0 / 3.6


@dataclass(frozen=True)
class DataSpec(Params):
    """How the identification data are generated (``ego train narma-l2``'s options read
    their bounds from here)."""

    samples: int = param(20000, "-", "at least this many (regressor, target) pairs in all", min=50, max=10_000_000)
    sample_period: float = param(0.05, "s", "controller sample period h", min=0.001, max=1.0)
    dt: float = param(0.01, "s", "model step: the scenario's control period", min=0.001, max=0.1)
    speed_min: float = param(20.0, "km/h", "entry speed range: low end", min=5.0, max=60.0)
    speed_max: float = param(40.0, "km/h", "entry speed range: high end", min=5.0, max=60.0)
    accel_min: float = param(0.0, "m/s^2", "axial acceleration range: low end", min=-2.0, max=2.0)
    accel_max: float = param(0.6, "m/s^2", "axial acceleration range: high end", min=-2.0, max=2.0)
    radius_min: float = param(12.0, "m", "curve radius range (log-uniform): low end", min=5.0, max=1000.0)
    radius_max: float = param(60.0, "m", "curve radius range (log-uniform): high end", min=5.0, max=1000.0)
    excitation: float = param(0.1, "rad", "largest excitation level", min=0.0, max=HALF_PI)
    hold_max: int = param(5, "-", "excitation levels last 1..hold_max samples", min=1, max=100)
    steer_limit: float = param(0.6, "rad", "steer limit", min=0.0, max=HALF_PI, min_exclusive=True)
    held_out_every: int = param(5, "-", "every n-th episode is held out", min=2, max=1000)

    def __post_init__(self) -> None:
        super().__post_init__()
        for low, high in (("speed_min", "speed_max"), ("accel_min", "accel_max"), ("radius_min", "radius_max")):
            if getattr(self, low) > getattr(self, high):
                raise ConfigError(
                    f"bad value for {low}: {getattr(self, low):g} (expected at most {high}={getattr(self, high):g})"
                )
        ratio = self.sample_period / self.dt
        if abs(ratio - round(ratio)) > 1e-9:
            raise ConfigError(
                f"bad value for sample_period: {self.sample_period:g} (expected a whole multiple of dt={self.dt:g} s)"
            )


@dataclass(frozen=True)
class TrainSpec(Params):
    """The networks and their training (torch, CPU)."""

    seed: int = param(0, "-", "seed of the data and the training", min=0, max=MAX_SEED)
    epochs: int = param(150, "-", "training epochs", min=1, max=100_000)
    batch: int = param(256, "-", "minibatch size", min=1, max=1_000_000)
    hidden: int = param(32, "-", "neurons in each hidden layer", min=1, max=1024)
    lr: float = param(3e-3, "-", "Adam's learning rate", min=0.0, max=1.0, min_exclusive=True)
    data: DataSpec = DataSpec()

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.data, DataSpec):
            raise ConfigError(f"bad data {self.data!r:.60} (expected a DataSpec)")


def curve_polyline(radius: float, side: float, approach: float = 15.0, exit_: float = 25.0) -> LanePolyline:
    """Straight along +x, a 90-degree arc of ``radius`` turning left (side +1) or right (-1)
    sampled every degree, then a straight."""
    pts = [(-approach, 0.0)]
    for k in range(91):
        a = math.radians(k)
        pts.append((radius * math.sin(a), side * (radius - radius * math.cos(a))))
    pts.append((radius, side * (radius + exit_)))
    return LanePolyline(pts)


def generate(spec: DataSpec, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Episodes until ``spec.samples`` pairs: X (n, features), y0 = y(k), y1 = y(k+1),
    u = u(k) and the episode index of each pair."""
    params = DynamicBicycleParams(slip_speed_floor=1.0)
    model = DynamicBicycle(params)
    per = round(spec.sample_period / spec.dt)
    step = model.stepper(spec.dt, 1)
    L, K = params.wheelbase, params.understeer_gradient
    rows, y0s, y1s, us, episodes = [], [], [], [], []
    episode = 0
    while len(rows) < spec.samples:
        v0 = rng.uniform(spec.speed_min, spec.speed_max) * KMH
        a_x = rng.uniform(spec.accel_min, spec.accel_max)
        radius = math.exp(rng.uniform(math.log(spec.radius_min), math.log(spec.radius_max)))
        side = 1.0 if rng.random() < 0.5 else -1.0
        lane = curve_polyline(radius, side)
        d0, psi0 = rng.uniform(-0.3, 0.3), rng.uniform(-0.05, 0.05)
        # feedback gains of the exciting driver, drawn per episode (varied closed loops)
        k_lat, k_head = rng.uniform(0.1, 0.4), rng.uniform(0.5, 1.5)
        x = (-12.0, v0, d0, 0.0, psi0, 0.0)
        end = lane.length - 10.0
        hist = None
        u_prev = [0.0, 0.0]
        level, hold = 0.0, 0
        while True:
            s, d, err, kappa = lane.frame(x[0], x[2], x[4])
            if s >= end or abs(d) > 2.5:
                break
            e_lat, e_head = -d, -err
            if hist is None:
                hist = [e_lat, e_head, e_lat, e_head]
            if hold == 0:
                level = rng.uniform(-spec.excitation, spec.excitation)
                hold = int(rng.integers(1, spec.hold_max + 1))
            hold -= 1
            u_ff = kappa * (L + K * x[1] * x[1])
            u = u_ff + k_lat * e_lat + k_head * e_head + level
            u = max(-spec.steer_limit, min(spec.steer_limit, u))
            ds = x[1] * math.cos(err) - x[3] * math.sin(err)
            row = (
                e_lat,
                e_head,
                hist[0],
                hist[1],
                hist[2],
                hist[3],
                u_prev[0],
                u_prev[1],
                x[1],
                a_x,
                kappa,
                lane.mean_curvature(s, ds * spec.sample_period),
            )
            for _ in range(per):
                x, _ = step(x, a_x, u)
            s1, d1, err1, _ = lane.frame(x[0], x[2], x[4])
            rows.append(row)
            y0s.append(e_lat + e_head)
            y1s.append(-d1 - err1)
            us.append(u)
            episodes.append(episode)
            hist = [e_lat, e_head, hist[0], hist[1]]
            u_prev = [u, u_prev[0]]
            if not all(map(math.isfinite, x)):
                raise RuntimeError("the identification run diverged")
        episode += 1
    return {
        "X": np.array(rows),
        "y0": np.array(y0s),
        "y1": np.array(y1s),
        "u": np.array(us),
        "episode": np.array(episodes),
    }


def held_out_mask(episode: np.ndarray, every: int) -> np.ndarray:
    """Every ``every``-th episode is held out; with fewer episodes than that (a tiny data
    set like the report's), the last 1/every of the samples."""
    if episode.max() + 1 >= every:
        return episode % every == every - 1
    mask = np.zeros(len(episode), dtype=bool)
    mask[len(episode) - max(1, len(episode) // every) :] = True
    return mask


def _mlp(torch, n_in: int, hidden: int):
    nn = torch.nn
    return nn.Sequential(nn.Linear(n_in, hidden), nn.Tanh(), nn.Linear(hidden, hidden), nn.Tanh(), nn.Linear(hidden, 1))


def train(spec: TrainSpec = TrainSpec(), out: Path = DEFAULT_MODEL, log=print) -> dict:
    """Generate the data, train f and g, write ``out`` (.npz) and its metadata (.json).
    Returns the metadata (errors, timings, sizes)."""
    import torch

    t0 = time.perf_counter()
    rng = np.random.default_rng(spec.seed)
    data = generate(spec.data, rng)
    t_data = time.perf_counter() - t0
    X, y0, y1, u, ep = data["X"], data["y0"], data["y1"], data["u"], data["episode"]
    held = held_out_mask(ep, spec.data.held_out_every)
    tr = ~held
    mean, std = X[tr].mean(axis=0), X[tr].std(axis=0)
    std[std < 1e-9] = 1.0
    dy = y1 - y0
    dy_scale = float(np.std(dy[tr]))
    # g's scale: least squares of dy on u (the average effect of a radian of steer)
    g_scale = float(abs(np.linalg.lstsq(np.column_stack([u[tr], np.ones(tr.sum())]), dy[tr], rcond=None)[0][0]))
    log(
        f"data: {len(X)} samples from {ep.max() + 1} episodes in {t_data:.1f} s "
        f"({tr.sum()} training, {held.sum()} held out); g_scale {g_scale:.4f} m/rad"
    )

    arrays, t_train = _fit(torch, spec, (X - mean) / std, dy / dy_scale, u * g_scale / dy_scale, tr, log)
    arrays = {"mean": mean, "std": std, "dy_scale": np.array(dy_scale), "g_scale": np.array(g_scale), **arrays}

    meta = {
        "features": list(FEATURES),
        "output": "y = e_lat + e_head one sample ahead",
        "sample_period": spec.data.sample_period,
        "seed": spec.seed,
        "train": {k: v for k, v in asdict(spec).items() if k != "data"},
        "data": asdict(spec.data),
        "samples": int(len(X)),
        "episodes": int(ep.max() + 1),
        "training_samples": int(tr.sum()),
        "held_out_samples": int(held.sum()),
        "data_seconds": round(t_data, 2),
        "train_seconds": round(t_train, 2),
        "torch": torch.__version__,
        "python": platform.python_version(),
    }
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as tmp, open(tmp, "wb") as f:  # the shipped model is read by running controllers
        np.savez(f, **arrays)
    from ego.control.narma import NarmaModel

    model = NarmaModel(arrays, meta)
    meta["errors"] = identification_errors(model, data, held)
    write_text(out.with_suffix(".json"), json.dumps(meta, indent=2) + "\n")
    e = meta["errors"]
    log(
        f"one-step error of y (m): training RMS {e['train_rms']:.2e}, held-out RMS "
        f"{e['held_out_rms']:.2e} ({100 * e['held_out_relative']:.1f} % of the held-out change "
        f"of y per sample, RMS {e['held_out_dy_rms']:.2e}); trained in {t_train:.1f} s"
    )
    log(f"wrote {out} and {out.with_suffix('.json').name}")
    return meta


def _fit(
    torch, spec: TrainSpec, x: np.ndarray, dy: np.ndarray, u: np.ndarray, tr: np.ndarray, log
) -> tuple[dict, float]:
    """Train f and g on the training rows ``tr`` (seeded, deterministic, one thread):
    ``x`` the normalised features, ``dy`` the scaled change of y, ``u`` the scaled steer.
    Returns the layers' weights and biases by name, and the training time (s)."""
    torch.manual_seed(spec.seed)
    torch.use_deterministic_algorithms(True)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        dtype = torch.float64
        xt = torch.tensor(x, dtype=dtype)
        target = torch.tensor(dy, dtype=dtype)
        ut = torch.tensor(u, dtype=dtype)
        f_net = _mlp(torch, x.shape[1], spec.hidden).to(dtype)
        g_net = _mlp(torch, x.shape[1], spec.hidden).to(dtype)
        with torch.no_grad():  # start g at the average effect (G = 1)
            g_net[-1].bias.fill_(1.0)
        opt = torch.optim.Adam([*f_net.parameters(), *g_net.parameters()], lr=spec.lr)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=spec.epochs)
        idx_train = torch.tensor(np.flatnonzero(tr))
        gen = torch.Generator().manual_seed(spec.seed)

        def loss_on(idx):
            pred = f_net(xt[idx]).squeeze(1) + g_net(xt[idx]).squeeze(1) * ut[idx]
            return torch.mean((pred - target[idx]) ** 2)

        t1 = time.perf_counter()
        for epoch in range(spec.epochs):
            perm = idx_train[torch.randperm(len(idx_train), generator=gen)]
            for i in range(0, len(perm), spec.batch):
                opt.zero_grad()
                loss = loss_on(perm[i : i + spec.batch])
                loss.backward()
                opt.step()
            sched.step()
            if (epoch + 1) % max(1, spec.epochs // 5) == 0:
                with torch.no_grad():
                    log(
                        f"epoch {epoch + 1}/{spec.epochs}: training loss "
                        f"{float(loss_on(idx_train)):.5f} (relative to var dy)"
                    )
        t_train = time.perf_counter() - t1
        arrays = {}
        for name, net in (("f", f_net), ("g", g_net)):
            layers = [m for m in net if isinstance(m, torch.nn.Linear)]
            for j, layer in enumerate(layers, 1):
                arrays[f"{name}_w{j}"] = layer.weight.detach().numpy().copy()
                arrays[f"{name}_b{j}"] = layer.bias.detach().numpy().copy()
    finally:
        torch.set_num_threads(threads)
    return arrays, t_train


def identification_errors(model, data: dict, held: np.ndarray) -> dict:
    """One-step-ahead prediction errors of y with the numpy model (what control uses)."""
    X, y1, u = data["X"], data["y1"], data["u"]
    pred = np.array([model.predict(X[i], u[i]) for i in range(len(X))])
    err = pred - y1
    dy = y1 - data["y0"]
    tr = ~held

    def rms(a):
        return float(np.sqrt(np.mean(a**2)))

    return {
        "train_rms": rms(err[tr]),
        "held_out_rms": rms(err[held]),
        "held_out_max": float(np.max(np.abs(err[held]))),
        "held_out_dy_rms": rms(dy[held]),
        "held_out_relative": rms(err[held]) / rms(dy[held]),
    }
