"""The static scene from frames sampled over a clip: their noise, one exposure, per-pixel medians (all, or of
the samples not excluded there), and the pixels no sample shows clear, filled from around them.

Arrays of a 4K clip's 60–119 samples are large: medians are taken a band of rows at a time, and masks found on
reduced samples are read at full size a band at a time (:class:`EnlargedMasks`), never all enlarged at once.
"""

from __future__ import annotations

import cv2
import numpy as np


def noise_sigma(samples: list[np.ndarray], background: np.ndarray) -> float:
    """Robust σ of I − B over a few samples (most pixels show the static scene)."""
    picks = samples[:: max(1, len(samples) // 8)]
    values = np.concatenate([(s.astype(np.float32) - background)[::2, ::2].ravel() for s in picks])
    return max(float(1.4826 * np.median(np.abs(values - np.median(values)))), 0.5)


def same_exposure(images: list[np.ndarray]) -> np.ndarray:
    """The samples brought to one exposure, as one (n, h, w) uint8 stack: each mapped by the gain and offset that
    best take it to the samples' median on every 4th pixel (two passes, the second without pixels off by > 3 MAD,
    at least 1.5 grey levels: the body; by the offset alone where the pixels kept span under 4 grey levels, as on
    a plain wall, whose gain they cannot tell: a fit there gave gains of 0.5 and offsets of 85); and, where a
    light's bands roll down the frame (mains flicker), by each row's own offset (:func:`_row_offsets`)."""
    grid = np.stack([im[::4, ::4] for im in images]).astype(np.float32)
    reference = np.median(grid, axis=0).ravel()
    out = np.empty((len(images), *images[0].shape), np.uint8)  # written in place: no second copy of the samples
    if np.ptp(reference) < 4:  # a flat picture: its gain is not defined, nothing to match
        out[:] = images
        return out
    for k, (image, small) in enumerate(zip(images, grid, strict=True)):
        values = small.ravel()
        keep = np.ones(values.size, bool)
        for _ in range(2):
            if np.ptp(reference[keep]) < 4:
                gain, offset = 1.0, float(np.median(values[keep] - reference[keep]))
            else:  # about the mean grey: well conditioned however narrow the span
                mean = float(reference[keep].mean())
                gain, at_mean = np.polyfit(reference[keep] - mean, values[keep], 1)
                offset = at_mean - gain * mean
            residual = values - (gain * reference + offset)
            keep = np.abs(residual) <= max(3 * 1.4826 * float(np.median(np.abs(residual))), 1.5)
        rows = _row_offsets(residual.reshape(small.shape), keep.reshape(small.shape), image.shape[0])
        if abs(gain - 1) < 0.005 and abs(offset) < 0.5 and rows is None:
            out[k] = image
        else:
            level = offset if rows is None else offset + rows[:, None]
            out[k] = np.clip(np.rint((image.astype(np.float32) - level) / gain), 0, 255)
    return out


def border_offset(signed: np.ndarray) -> np.ndarray | float:
    """The window's offset from the scene as a line in the row, o(y) = a + b (y − ȳ), fitted to its border's
    I − B (its left and right columns row by row, its top and bottom rows at their ends), twice, the second time
    without the pixels more than 3 MAD (at least 1.5 grey levels) off the first (a string, a shadow); the median
    where the window is too short. A level follows slow exposure drift; the slope, a light's bands rolling down a
    rolling-shutter frame (mains flicker, with the samples' rows brought to one exposure:
    :func:`pendulum.tracking.scene_stack.same_exposure`)."""
    h = signed.shape[0]
    rows = np.r_[np.arange(h), np.arange(h), np.zeros(signed.shape[1]), np.full(signed.shape[1], h - 1)]
    values = np.r_[signed[:, 0], signed[:, -1], signed[0], signed[-1]].astype(np.float64)
    if h < 8:
        return float(np.median(values))
    y = rows - 0.5 * (h - 1)
    keep = np.ones(values.size, bool)
    for _ in range(2):  # least squares in closed form (a call of np.polyfit per frame cost 4 % of a body's track)
        ys, vs = y[keep], values[keep]
        y_mean, v_mean = float(ys.mean()), float(vs.mean())
        spread = float(((ys - y_mean) ** 2).sum())
        slope = float(((ys - y_mean) * (vs - v_mean)).sum()) / spread if spread > 0 else 0.0
        level = v_mean - slope * y_mean
        residual = values - (level + slope * y)
        keep = np.abs(residual) <= max(3 * 1.4826 * float(np.median(np.abs(residual))), 1.5)
    return (level + slope * (np.arange(h) - 0.5 * (h - 1)))[:, None].astype(np.float32)


ROW_BAND_SIGMAS = 5.0  # row offsets whose spread is this many times their own noise (and ≥ 1 grey level): bands


def _row_offsets(residual: np.ndarray, keep: np.ndarray, height: int) -> np.ndarray | None:
    """Per image row, the offset that a light's bands rolling down a rolling-shutter frame (mains flicker) add
    along the rows, from the median residual of each sampled row (every 4th) over its kept pixels, continued to
    every row (not smoothed: a band's slope is up to 4 grey levels from one sampled row to the next); None where
    their spread is not ROW_BAND_SIGMAS times the noise of a row's median and at least 1 grey level (no bands:
    the sample as it was)."""
    masked = np.where(keep, residual, np.nan)
    counts = keep.sum(axis=1)
    if residual.shape[0] < 10 or np.any(counts < 8):
        return None
    with np.errstate(all="ignore"):
        medians = np.nanmedian(masked, axis=1)
    sigma = 1.4826 * float(np.median(np.abs(residual[keep])))
    noise = 1.25 * sigma / np.sqrt(float(np.median(counts)))
    spread = float(np.std(medians))
    if spread < max(1.0, ROW_BAND_SIGMAS * noise):
        return None
    return np.interp(np.arange(height), 4 * np.arange(medians.size), medians).astype(np.float32)


MEDIAN_ROWS = 64  # image rows per band of the per-pixel medians (memory, not results)


def median_scene(stack: np.ndarray, rows: int = MEDIAN_ROWS) -> np.ndarray:
    """Per-pixel median of the (n, h, w) samples as float32, ``rows`` image rows at a time (``np.median`` sorts a
    copy of what it is given: a band, not the whole stack; the same values)."""
    out = np.empty(stack.shape[1:], np.float32)
    for top in range(0, stack.shape[1], rows):
        out[top : top + rows] = np.median(stack[:, top : top + rows], axis=0)
    return out


class EnlargedMasks:
    """Per-sample masks found on reduced samples, read at full size as ``cv2.resize`` with ``INTER_NEAREST``
    enlarges them (:func:`nearest_source`), a band of rows at a time: 60–119 full-size masks of a
    4K clip would take 0.5–1 GB."""

    def __init__(self, small: np.ndarray, shape: tuple[int, int]):
        self.small = small
        self.shape = (len(small), *shape)
        self.rows, self.cols = (
            nearest_source(full, reduced) for full, reduced in zip(shape, small.shape[1:], strict=True)
        )

    def __len__(self) -> int:
        return self.shape[0]

    def band(self, top: int, bottom: int) -> np.ndarray:
        """Full-size masks of image rows ``top`` to ``bottom`` (exclusive): (n, rows, width)."""
        return self.small[:, self.rows[top:bottom]][:, :, self.cols]

    def enlarged(self, image: np.ndarray) -> np.ndarray:
        """A per-pixel image of the reduced size at full size (nearest)."""
        return image[self.rows][:, self.cols]

    def any(self) -> bool:
        return bool(self.small.any())

    def any_over_samples(self) -> np.ndarray:
        return self.enlarged(self.small.any(axis=0))

    def count_over_samples(self) -> np.ndarray:
        return self.enlarged(self.small.sum(axis=0))

    def extent(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The full-size rows and columns sample ``k``'s mask reaches."""
        mask = self.small[k]
        return np.flatnonzero(mask.any(axis=1)[self.rows]), np.flatnonzero(mask.any(axis=0)[self.cols])


def nearest_source(full: int, small: int) -> np.ndarray:
    """The reduced index each of ``full`` indices reads when ``cv2.resize`` enlarges ``small`` with
    ``INTER_NEAREST``: ⌊i · (1 / (full / small))⌋, the scale inverted as OpenCV does (⌊i · small / full⌋ is one
    lower where that product is a whole number, e.g. 1058 rows from 352)."""
    return np.minimum((np.arange(full) * (1.0 / (full / small))).astype(int), small - 1)


def as_masks(excluded) -> EnlargedMasks:
    """``excluded`` as :class:`EnlargedMasks` (full-size masks: enlarged from themselves)."""
    return excluded if isinstance(excluded, EnlargedMasks) else EnlargedMasks(excluded, excluded.shape[1:])


def masked_median(stack: np.ndarray, excluded, fallback: np.ndarray) -> np.ndarray:
    """Per pixel, the median of the samples not excluded there (``excluded``: (n, h, w) masks, or
    :class:`EnlargedMasks`); where fewer than :func:`min_clear_samples` are left (:func:`unseen`), ``fallback``
    filled from its surroundings there (:func:`fill`)."""
    excluded = as_masks(excluded)
    background = fallback.copy()
    union = excluded.any_over_samples()
    if union.any():
        hidden = np.zeros(background.shape, bool)
        for top in range(0, stack.shape[1], MEDIAN_ROWS):  # a band of rows at a time: a 4K clip's samples are large
            band = slice(top, top + MEDIAN_ROWS)
            inside = union[band]
            if not inside.any():
                continue
            column = stack[:, band][:, inside].astype(np.float32)
            column[excluded.band(top, top + MEDIAN_ROWS)[:, inside]] = np.nan
            column.sort(axis=0)  # NaN last: the median of the first `valid` values of each pixel
            valid = np.isfinite(column).sum(axis=0)
            lower = np.take_along_axis(column, np.maximum((valid - 1) // 2, 0)[None], axis=0)[0]
            upper = np.take_along_axis(column, np.maximum(valid // 2, 0)[None], axis=0)[0]
            enough = valid >= min_clear_samples(len(stack))
            background[band][inside] = np.where(enough, 0.5 * (lower + upper), fallback[band][inside])
            hidden[band][inside] = ~enough
        if hidden.any():  # never seen clear (a body there, or a ghost of it, in nearly every sample): its surroundings
            background = fill(background, hidden)
    return background


def min_clear_samples(n: int) -> int:
    """Samples that must show a pixel clear for the scene there to be their median: max(5, n/10) of ``n``."""
    return max(5, n // 10)


def unseen(excluded) -> np.ndarray:
    """The pixels no sample shows clear (``excluded``: as in :func:`masked_median`): a moving object there in all
    but fewer than :func:`min_clear_samples` (:func:`masked_median` fills them from their surroundings)."""
    excluded = as_masks(excluded)
    n = len(excluded)
    return excluded.any_over_samples() & (n - excluded.count_over_samples() < min_clear_samples(n))


def fill(scene: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``scene`` with the ``mask`` pixels filled from their surroundings (Navier–Stokes inpainting: a plain wall
    exactly, a gradient of 0.2 grey levels per px over a 20 px radius to 1.7 (90th percentile; 2.8 at most);
    Telea's is 1.5 off a plain one)."""
    return cv2.inpaint(scene.astype(np.float32), mask.astype(np.uint8), 3, cv2.INPAINT_NS)
