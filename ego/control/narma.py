"""Report 002's NARMA-L2 curve controller (as in MATLAB's Deep Learning Toolbox).

Identification: with the controller's sample period ``h`` the plant output one sample
ahead is modelled as affine in the current steer,

    y(k+1) = f(x(k)) + g(x(k)) * u(k),       y = e_lat + e_head   (see ego.control.curve)

where the regressor x(k) holds the errors now and at the two previous samples, the two
previous steers, the speed, the axial acceleration, the lane curvature here and its mean
over the stretch the car covers in the next sample (the road preview, from
``obs.lane``; without it the arc's start and end are where the model is worst) (``FEATURES``);
f and g are two small tanh networks trained in torch (``ego train narma-l2``). Control:
the steer that makes the model's next output equal the reference r(k+1) = rho * y(k),

    u(k) = (r(k+1) - f(x(k))) / g(x(k)),

with |g| floored at ``g_min`` and u saturated at ``steer_limit``. The steer is held for
the sample period ``h`` (a whole number of control periods). Inference is numpy with
preallocated buffers; torch is only needed to train.
"""

from __future__ import annotations

import zipfile
import zlib
from dataclasses import dataclass
from functools import lru_cache
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np

from ego.checks import check_input_file, finite_number, read_json
from ego.control.base import Observation
from ego.control.curve import PedalLoop, PedalParams
from ego.params import HALF_PI, ConfigError, param

#: the regressor, in order; ``_1``/``_2`` are one and two samples back, u the steer (rad)
FEATURES = (
    "e_lat",
    "e_head",
    "e_lat_1",
    "e_head_1",
    "e_lat_2",
    "e_head_2",
    "u_1",
    "u_2",
    "speed",
    "a_x",
    "curvature",
    "curvature_ahead",
)
#: where the shipped networks live (written by ``ego train narma-l2``)
TRAINED_DIR = Path(str(files("ego.control") / "trained"))  # package data, installed or not
DEFAULT_MODEL = TRAINED_DIR / "narma_l2.npz"


class NarmaModel:
    """The trained f and g networks as numpy arrays, evaluated without allocations.

    Each network is x_n = (x - mean) / std -> tanh(W1 x_n + b1) -> tanh(W2 . + b2) ->
    w3 . + b3; then f = y + dy_scale * F and g = g_scale * G.
    """

    def __init__(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        self.meta = meta
        self.h = float(meta["sample_period"])
        self.mean = np.asarray(arrays["mean"], dtype=float)
        self.inv_std = 1.0 / np.asarray(arrays["std"], dtype=float)
        self.dy_scale = float(arrays["dy_scale"])
        self.g_scale = float(arrays["g_scale"])
        self.nets = []
        for name in ("f", "g"):
            w1, b1 = np.asarray(arrays[f"{name}_w1"], float), np.asarray(arrays[f"{name}_b1"], float)
            w2, b2 = np.asarray(arrays[f"{name}_w2"], float), np.asarray(arrays[f"{name}_b2"], float)
            w3, b3 = np.asarray(arrays[f"{name}_w3"], float).ravel(), float(np.asarray(arrays[f"{name}_b3"]).ravel()[0])
            self.nets.append((w1, b1, w2, b2, w3, b3, np.empty(len(b1)), np.empty(len(b2))))
        self._xn = np.empty(len(FEATURES))

    @classmethod
    def load(cls, path: str | Path = DEFAULT_MODEL) -> NarmaModel:
        """The weights (.npz) and their metadata (the .json beside them), each checked: a
        file that is not what ``ego train narma-l2`` writes is a ConfigError naming it."""
        path = Path(path)
        meta_path = path.with_suffix(".json")
        if path.suffix == ".npz" and not path.exists():
            raise ConfigError(f"no trained NARMA-L2 model at {path} (train one: ego train narma-l2)")
        check_input_file(path, "NARMA-L2 model", ".npz")
        if not meta_path.exists():
            raise ConfigError(
                f"bad NARMA-L2 model {str(path)!r}: its metadata {meta_path.name} is missing "
                "(ego train narma-l2 writes both)"
            )
        meta = read_json(meta_path, "NARMA-L2 metadata")
        try:
            from ego.control.npz import check_npz_members

            check_npz_members(path)  # every member npy data of a size the file can hold
            with np.load(path, allow_pickle=False) as data:
                arrays = {k: data[k] for k in data.files}
        except ConfigError as exc:
            raise ConfigError(f"bad NARMA-L2 model {str(path)!r}: {exc}") from None
        except (OSError, ValueError, EOFError, AttributeError, MemoryError, zipfile.BadZipFile, zlib.error) as exc:
            raise ConfigError(
                f"bad NARMA-L2 model {str(path)!r}: not a readable .npz file ({type(exc).__name__})"
            ) from None
        problem = _meta_problem(meta) or _arrays_problem(arrays)
        if problem:
            raise ConfigError(f"bad NARMA-L2 model {str(path)!r}: {problem} (retrain: ego train narma-l2)")
        return cls(arrays, meta)

    def _net(self, i: int, xn: np.ndarray) -> float:
        w1, b1, w2, b2, w3, b3, h1, h2 = self.nets[i]
        np.dot(w1, xn, out=h1)
        h1 += b1
        np.tanh(h1, out=h1)
        np.dot(w2, h1, out=h2)
        h2 += b2
        np.tanh(h2, out=h2)
        return float(w3 @ h2) + b3

    def f_g(self, x: np.ndarray) -> tuple[float, float]:
        """(f, g) at regressor ``x`` (in ``FEATURES`` order)."""
        xn = self._xn
        np.subtract(x, self.mean, out=xn)
        xn *= self.inv_std
        y = x[0] + x[1]
        return y + self.dy_scale * self._net(0, xn), self.g_scale * self._net(1, xn)

    def predict(self, x: np.ndarray, u: float) -> float:
        """The model's y(k+1) for regressor ``x`` and steer ``u``."""
        f, g = self.f_g(x)
        return f + g * u


#: the smallest standard deviation a feature may have: 1/std stays finite and the
#: normalised regressor does not lose every digit
MIN_STD = 1e-9


def _meta_problem(meta: Any) -> str | None:
    """What is wrong with a model's metadata (or None)."""
    if not isinstance(meta, dict):
        return "its metadata is not a JSON object"
    h: Any = meta.get("sample_period")
    if not finite_number(h) or not 0.001 <= h <= 1.0:
        return f"its metadata's sample_period is {h!r:.40} (expected 0.001 to 1 s)"
    if meta.get("features") != list(FEATURES):
        return f"it was trained on features {meta.get('features')!r:.80}, this ego expects {list(FEATURES)}"
    return None


def _arrays_problem(arrays: dict[str, np.ndarray]) -> str | None:
    """What is wrong with a model's arrays (or None): every array present, numeric, finite,
    with the shapes of two tanh networks on ``FEATURES``."""
    n = len(FEATURES)
    names = ["mean", "std", "dy_scale", "g_scale"] + [
        f"{net}_{k}" for net in "fg" for k in ("w1", "b1", "w2", "b2", "w3", "b3")
    ]
    for name in names:
        if name not in arrays:
            return f"the array {name} is missing"
        a = arrays[name]
        if not np.issubdtype(a.dtype, np.number) or np.issubdtype(a.dtype, np.complexfloating):
            return f"the array {name} is not numeric ({a.dtype})"
        if not np.isfinite(a).all():
            return f"the array {name} holds NaN or infinite values"
    shapes: dict[str, tuple[int, ...]] = {"mean": (n,), "std": (n,)}
    for net in "fg":
        h1, h2 = arrays[f"{net}_b1"].size, arrays[f"{net}_b2"].size
        shapes.update({f"{net}_w1": (h1, n), f"{net}_b1": (h1,), f"{net}_w2": (h2, h1), f"{net}_b2": (h2,)})
    for name, shape in shapes.items():
        if arrays[name].shape != shape:
            return f"the array {name} has shape {arrays[name].shape} (expected {shape})"
    for name in ("dy_scale", "g_scale", "f_b3", "g_b3"):
        if arrays[name].size != 1:
            return f"the array {name} has {arrays[name].size} values (expected one)"
    for net in "fg":
        if arrays[f"{net}_w3"].size != arrays[f"{net}_b2"].size:
            return f"the array {net}_w3 has {arrays[f'{net}_w3'].size} values (expected {arrays[f'{net}_b2'].size})"
    if (arrays["std"] <= 0).any():
        return "the array std has values that are not positive"
    if (arrays["std"] < MIN_STD).any():
        return (
            f"the array std has values below {MIN_STD:g} (1/std would overflow; "
            f"smallest {float(arrays['std'].min()):g})"
        )
    return None


@lru_cache(maxsize=4)
def load_model(path: str = str(DEFAULT_MODEL)) -> NarmaModel:
    """A trained model, loaded once per process."""
    return NarmaModel.load(path)


@dataclass(frozen=True)
class NarmaL2Params(PedalParams):
    """NARMA-L2 control on the shipped networks (trained by ``ego train narma-l2``)."""

    rho: float = param(
        0.8, "-", "reference r(k+1) = rho * y(k): the error kept per sample (0: deadbeat)", min=0, max=0.99
    )
    move_penalty: float = param(
        0.002,
        "m^2/rad^2",
        "weight lambda on steer changes (0: the plain inverse u = (r - f) / g, which rings; see the module)",
        min=0,
        max=100.0,
    )
    g_min: float = param(0.01, "m/rad", "floor on |g| (the steer's effect per sample)", min=1e-4, max=10.0)
    steer_limit: float = param(0.6, "rad", "|delta| limit", min=0, max=HALF_PI, min_exclusive=True)
    model: str = param("", "-", "trained model (.npz); empty: the one shipped with ego")

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.model:  # read and check it now, before any run starts
            load_model(self.model)


class NarmaL2Controller:
    """u = (rho y - f) / g every sample period, held in between."""

    def __init__(self, params: NarmaL2Params, dt: float) -> None:
        self.params = p = params
        self.net = load_model(p.model or str(DEFAULT_MODEL))
        ratio = self.net.h / dt
        if abs(ratio - round(ratio)) > 1e-6 or round(ratio) < 1:
            raise ConfigError(
                f"bad value for dt: {dt} (the NARMA-L2 model samples every {self.net.h} s; dt must divide it)"
            )
        self.every = round(ratio)
        self.pedal = PedalLoop(p, dt)
        self.x = np.zeros(len(FEATURES))
        self.reset()

    def reset(self, *, seed: int | None = None) -> None:
        self.pedal.reset()
        self.k = 0
        self.first = True
        self.u = 0.0
        self.f = self.g = 0.0
        self.x[:] = 0.0

    def step(self, obs: Observation) -> tuple[float, float]:
        e_lat, e_head = obs.d_ref - obs.d, -obs.heading_error
        a_x = self.pedal.step(obs, e_head)
        k = self.k
        self.k = k + 1
        if k % self.every:
            return a_x, self.u
        x = self.x
        if self.first:  # no history yet: as if it had been like this (the plant at rest)
            x[0:6] = (e_lat, e_head, e_lat, e_head, e_lat, e_head)
            self.first = False
        else:
            x[4], x[5], x[2], x[3] = x[2], x[3], x[0], x[1]
            x[0], x[1] = e_lat, e_head
        x[7], x[6] = x[6], self.u
        x[8], x[9], x[10] = obs.speed, a_x, obs.curvature
        lane = obs.lane
        x[11] = lane.mean_curvature(obs.s, obs.ds * self.net.h) if lane is not None else obs.curvature
        p = self.params
        f, g = self.net.f_g(x)
        if abs(g) < p.g_min:
            g = p.g_min if g >= 0.0 else -p.g_min
        lam = p.move_penalty
        u = (g * (p.rho * (e_lat + e_head) - f) + lam * self.u) / (g * g + lam)
        lim = p.steer_limit
        self.u = lim if u > lim else (-lim if u < -lim else u)
        self.f, self.g = f, g
        return a_x, self.u

    #: the networks' f (the error next sample, m) and g (its change per rad of steer)
    signal_units = {"narma_f": "m", "narma_g": "m/rad", "a_x_cmd": "m/s^2"}

    def signals(self) -> dict[str, float]:
        return {"narma_f": self.f, "narma_g": self.g, "a_x_cmd": self.pedal.a_x}
