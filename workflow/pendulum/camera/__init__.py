"""Camera: raw videos in, frames out: decoding and frame timing, the lens calibration, the swing plane's view."""
