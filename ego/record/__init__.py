"""Recording runs: the recorder interface, a no-op recorder and Rerun files."""

from ego.record.base import NullRecorder, Recorder, Scene, Series, box_outlines, lane_edges
from ego.record.rerun_recorder import RerunRecorder

__all__ = ["NullRecorder", "Recorder", "RerunRecorder", "Scene", "Series", "box_outlines", "lane_edges"]
