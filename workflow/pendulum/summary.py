"""Fit documents as written to results/fits, and the summary table (the paper's Tables 2 and 3)."""

from __future__ import annotations

from dataclasses import asdict

import pandas as pd

from pendulum.physics import ADDED_MASS
from pendulum.records import FitSettings


def fit_document(fit: dict, *, variant: str, rig: dict, sources: list[str], settings: FitSettings) -> dict:
    """A fit as written to results/fits: what was fitted, to what, with which settings, then the fit."""
    return {
        "variant": variant,
        "terms": fit["terms"],
        "rig": rig,
        "sources": list(sources),
        "settings": asdict(settings),
        **{k: v for k, v in fit.items() if k != "terms"},
    }


PHYSICAL_COLUMNS = (ADDED_MASS, "drag_area_m2", "drag_coefficient", "linear_damping_nm_s", "friction_torque_nm")


def summary_table(documents: list[dict]) -> pd.DataFrame:
    """One row per (variant, trial or joint fit): the paper's Tables 2 and 3 with intervals and flags."""
    rows = []
    for doc in documents:
        fits = [(doc["trial"], doc)] if "trial" in doc else [(f"joint:{rig}", d) for rig, d in doc["rigs"].items()]
        for label, fit in fits:
            kc = fit["keulegan_carpenter_number"]
            first = next(iter(fit["trials"].values()))
            row = {
                "variant": fit["variant"],
                "fit": label,
                "n_trials": len(fit["trials"]),
                "theta0_deg": first["theta0_deg"] if len(fit["trials"]) == 1 else None,
                "kc_min": min(kc) if isinstance(kc, list) else kc,
                "kc_max": max(kc) if isinstance(kc, list) else kc,
                "n_samples": fit["n_samples"],
                "rms_deg": fit["rms_deg"],
                "rms_arc_m": fit["rms_arc_m"],
                "aic": fit["aic"],
                "bic": fit["bic"],
                "consistency": fit.get("consistency", {}).get("verdict"),
                "n_warnings": len(fit["warnings"]),
            }
            for name in PHYSICAL_COLUMNS:
                entry = fit["parameters"].get(name)
                row[name] = entry["value"] if entry else None
                row[f"{name}_stderr"] = entry["stderr"] if entry else None
                row[f"{name}_ci95_low"] = entry["ci95"][0] if entry else None
                row[f"{name}_ci95_high"] = entry["ci95"][1] if entry else None
                row[f"{name}_at_bound"] = entry["at_bound"] if entry else None
                row[f"{name}_identifiable"] = entry["identifiable"] if entry else None
            rows.append(row)
    return pd.DataFrame(rows)
