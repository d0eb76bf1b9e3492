"""Tracking: frames in, tracks out: the marker (or the body's silhouette) found, followed and checked frame by frame."""
