"""stereodet: KITTI I/O, KITTI evaluation and stereo features, at C++ speed.

The C++ toolkit's Python module. Everything runs in C++ with the GIL released, so threads run in
parallel; bad input raises ValueError (stereodet.ParseError for a bad line of a file, with the same
"FILE:LINE: field F: message" text as the command line) or OSError (files), never a crash.

    import stereodet
    stereodet.__version__

Evaluation (stereodet.evaluation, re-exported here): evaluate() on folders or on the annotation
dicts of OpenPCDet / mmdetection3d, get_official_eval_result() (a drop-in for OpenPCDet's),
filter_sweep(), compare().

Submodules: stereodet.kitti (labels, detections, calibrations, velodyne scans to and from numpy),
stereodet.mmdet3d (kitti_eval, a drop-in for mmdetection3d's),
stereodet.stereo (disparity, depth, height, RGB-H / RGB-D, point clouds from numpy images; loads
OpenCV on first use). stereodet.Detector runs a trained detector of any family on numpy frames
(loads LibTorch on first use; built with the models module). The evaluation functions are at the
top level. docs/python.md is the guide.
"""

from . import kitti, mmdet3d
from ._core import ParseError, __version__
from .evaluation import (ClassResult, ClassSpec, EvalOptions, EvalResult, analyze_errors, compare,
                         evaluate, filter_sweep, get_official_eval_result)

__all__ = ["ClassResult", "ClassSpec", "EvalOptions", "EvalResult", "ParseError", "__version__",
           "Detector", "analyze_errors", "compare", "evaluate", "filter_sweep", "get_official_eval_result", "kitti",
           "mmdet3d", "stereo"]


def __getattr__(name: str):
    # stereodet.stereo loads OpenCV, stereodet.Detector LibTorch: only when first used.
    import importlib

    if name == "stereo":
        return importlib.import_module(".stereo", __name__)
    if name == "Detector":
        try:
            detector = importlib.import_module("._detector", __name__)
        except ImportError as e:
            raise ImportError("stereodet.Detector needs the _detector extension, built with the "
                              "models module (LibTorch: cmake -DSTEREODET_BUILD_MODELS=ON, the "
                              "default, with libtorch-dev installed)") from e
        return detector.Detector
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | {"stereo", "Detector"})
