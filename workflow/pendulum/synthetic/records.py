"""Synthetic angle records without video: a model's decay with tracking-like noise, for fit and discovery tests.

:func:`synthetic_angle_table` simulates an angle table as the angles stage writes it (time since
release) with :func:`pendulum.model.physics.simulate`, the same equations the fitter uses, plus a rest
offset, a drifting zero and a periodic disturbance torque (effects outside the library);
:func:`angle_noise_rad` adds white plus AR(1) noise like the tracker's; :func:`hidden_effect_table`
hides the effects whose coefficients a truth holds in such a table, for discovery tests.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from pendulum.model.effects import effects_for
from pendulum.model.physics import PendulumModel, simulate
from pendulum.model.rig import Rig

if TYPE_CHECKING:
    from pendulum.synthetic.specs import PeriodicTorque


def angle_noise_rad(
    rng: np.random.Generator, n: int, white_deg: float = 0.004, correlated_deg: float = 0.003, correlation: float = 0.8
) -> np.ndarray:
    """Tracking-like angle noise: white plus an AR(1) part e_t = ρ e_{t−1} + √(1−ρ²) σ w_t.

    The defaults match the demo videos' measured angle errors (≈0.005° RMS,
    lag-1 autocorrelation 0.3–0.5).
    """
    white = rng.standard_normal(n) * math.radians(white_deg)
    drive = rng.standard_normal(n) * math.radians(correlated_deg)
    coloured = np.empty(n)
    coloured[0] = drive[0]
    scale = math.sqrt(1 - correlation**2)
    for i in range(1, n):
        coloured[i] = correlation * coloured[i - 1] + scale * drive[i]
    return white + coloured


def synthetic_angle_table(
    model: PendulumModel,
    truth: dict,
    release_deg: float,
    *,
    fps: float = 30.0,
    duration_s: float = 22.0,
    rest_offset_deg: float = 0.0,
    rng: np.random.Generator | None = None,
    zero_drift_deg: float = 0.0,
    disturbance: PeriodicTorque | None = None,
    **noise,
) -> pd.DataFrame:
    """An angle record as the angles stage writes it (time since release), from the model itself.

    θ_k = x(t_k) + δ + Δ t_k / duration_s + noise, x simulated from rest at the release (t = 0) with
    every effect of ``model`` (the history force's memory starts there) plus ``disturbance(t)``; δ is
    ``rest_offset_deg``, Δ ``zero_drift_deg`` (a zero drifting linearly, outside the library).
    """
    times = np.arange(1, int(duration_s * fps) + 1) / fps
    grid = np.concatenate([[0.0], times])
    if disturbance is None:
        theta, _ = simulate(model, truth, math.radians(release_deg), 0.0, grid, substeps=8)
    else:
        theta, _ = simulate(
            model, truth, math.radians(release_deg), 0.0, grid, substeps=8, external_torque_nm=disturbance
        )
    theta = theta[1:] + math.radians(rest_offset_deg)
    if zero_drift_deg:
        theta = theta + math.radians(zero_drift_deg) * times / duration_s
    if rng is not None:
        theta = theta + angle_noise_rad(rng, times.size, **noise)
    return pd.DataFrame({"time_s": times, "theta_rad": theta, "flag": "ok"})


def hidden_effect_table(
    rig: dict | Rig,
    truth: dict,
    release_deg: float,
    *,
    effects: tuple[str, ...] | None = None,
    seed: int | None = None,
    **options,
) -> pd.DataFrame:
    """An angle table with effects hidden in it, for discovery tests (no video): the truth decides the physics.

    ``truth`` maps parameter names to values (``added_mass_kg`` plus one coefficient per hidden
    library effect, e.g. ``history_coefficient_kg_per_sqrt_s``); ``effects`` defaults to the library
    effects whose coefficients ``truth`` holds. ``seed`` adds tracking-like noise (None: noise-free).
    ``options`` go to :func:`synthetic_angle_table`: fps, duration_s, rest_offset_deg, zero_drift_deg,
    disturbance (a :class:`PeriodicTorque`) and the noise levels.
    """
    rig = rig if isinstance(rig, Rig) else Rig.from_mapping(rig)
    model = PendulumModel(rig, effects_for(truth) if effects is None else tuple(effects))
    rng = None if seed is None else np.random.default_rng(seed)
    return synthetic_angle_table(model, truth, release_deg, rng=rng, **options)
