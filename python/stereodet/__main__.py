"""`python3 -m stereodet eval`: stereodet's evaluation on the files OpenPCDet and mmdetection3d write.

    python3 -m stereodet eval --gt kitti_infos_val.pkl --det result.pkl [eval options]
    python3 -m stereodet eval --gt KITTI_ROOT --det result.pkl --split val
    python3 -m stereodet eval --gt KITTI_ROOT --det RESULTS_DIR --split val   # as `stereodet eval`

--gt: a ground-truth infos pickle (OpenPCDet's kitti_infos_*.pkl, mmdetection3d 0.x's: a list of
per-frame dicts with "annos"), or a label folder as `stereodet eval` takes it. --det: a results
pickle (OpenPCDet's result.pkl, mmdetection3d 0.x's formatted results: a list of per-frame
annotation dicts), or a detection folder. The frames are matched by id where both sides name them
(the infos' point_cloud.lidar_idx or image.image_idx, the results' frame_id), else by position; a
frame of the ground truth without results counts as one without detections, a result of a frame
the ground truth does not have is an error. The table printed and the --out folder are
`stereodet eval`'s (stereodet.evaluate: the same numbers to the last digit).

A pickle can run code when loaded; these are read with an unpickler that builds only plain data
(dicts, lists, strings, numbers) and numpy arrays, and refuses anything else by name.
"""
import argparse
import io
import os
import pickle
import sys
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

import stereodet

# What a results or infos pickle may build besides Python's plain types: numpy arrays, dtypes and
# scalars, under numpy 1's and numpy 2's module names.
_ALLOWED = {
    ("numpy.core.multiarray", "_reconstruct"), ("numpy._core.multiarray", "_reconstruct"),
    ("numpy.core.multiarray", "scalar"), ("numpy._core.multiarray", "scalar"),
    ("numpy", "ndarray"), ("numpy", "dtype"), ("collections", "OrderedDict"),
}


class _DataOnlyUnpickler(pickle.Unpickler):
    def __init__(self, file, source: str):
        super().__init__(file)
        self.source = source

    def find_class(self, module: str, name: str):
        if (module, name) in _ALLOWED:
            return super().find_class(module, name)
        raise pickle.UnpicklingError(
            f"{self.source}: the pickle holds a {module}.{name} object; only plain data and numpy "
            "arrays are read (loading others could run code)")


def load_pickle(path: Path) -> Any:
    """A pickle of plain data and numpy arrays (see _DataOnlyUnpickler)."""
    with open(path, "rb") as f:
        data = f.read()
    try:
        return _DataOnlyUnpickler(io.BytesIO(data), str(path)).load()
    except pickle.UnpicklingError:
        raise
    except Exception as error:  # a truncated or foreign file: one message naming it
        raise ValueError(f"{path}: not a readable pickle ({error})") from None


def _frame_id(entry: Dict[str, Any]) -> Optional[str]:
    """The frame id an infos entry or a results entry names, as KITTI's six digits where numeric."""
    for key, sub in (("point_cloud", "lidar_idx"), ("image", "image_idx")):
        if isinstance(entry.get(key), dict) and sub in entry[key]:
            return _normalise_id(entry[key][sub])
    if "frame_id" in entry:
        return _normalise_id(entry["frame_id"])
    return None


def _normalise_id(value: Any) -> str:
    if isinstance(value, np.ndarray):
        value = value.reshape(-1)[0]
    text = str(value)
    return f"{int(text):06d}" if text.isdigit() else text


def gt_annos_from_infos(infos: Any, source: str) -> Tuple[List[dict], List[Optional[str]]]:
    """The "annos" of each frame of an infos pickle, and the frames' ids (None where unnamed)."""
    if isinstance(infos, dict) and "data_list" in infos:
        raise ValueError(f"{source}: an mmdetection3d 1.x infos file (data_list of instances); "
                         "convert it with mmdetection3d's 0.x tools, or evaluate label folders")
    if not isinstance(infos, list) or not infos:
        raise ValueError(f"{source}: expected a list of per-frame infos, got {type(infos).__name__}")
    annos, ids = [], []
    for i, info in enumerate(infos):
        if not isinstance(info, dict) or not isinstance(info.get("annos"), dict):
            raise ValueError(f"{source}: frame {i} has no 'annos' dict (ground-truth infos need "
                             "the annotations: the val or train infos, not test)")
        annos.append(info["annos"])
        ids.append(_frame_id(info))
    return annos, ids


def det_annos_from_results(results: Any, source: str) -> Tuple[List[dict], List[Optional[str]]]:
    """The per-frame annotation dicts of a results pickle, and their ids (None where unnamed)."""
    if isinstance(results, dict) and isinstance(results.get("annos"), list):
        results = results["annos"]
    if not isinstance(results, list):
        raise ValueError(f"{source}: expected a list of per-frame result dicts, got "
                         f"{type(results).__name__}")
    for i, r in enumerate(results):
        if not isinstance(r, dict) or "name" not in r:
            raise ValueError(f"{source}: frame {i} is not an annotation dict (no 'name'): "
                             "OpenPCDet's result.pkl or mmdetection3d's formatted KITTI results "
                             "hold one per frame")
    return results, [_frame_id(r) for r in results]


def empty_annos() -> dict:
    return {"name": np.array([], dtype="<U10"), "truncated": np.zeros(0), "occluded": np.zeros(0),
            "alpha": np.zeros(0), "bbox": np.zeros((0, 4)), "dimensions": np.zeros((0, 3)),
            "location": np.zeros((0, 3)), "rotation_y": np.zeros(0), "score": np.zeros(0)}


def align(gt: Tuple[List[dict], List[Optional[str]]], det: Tuple[List[dict], List[Optional[str]]],
          det_source: str) -> List[dict]:
    """The results in the ground truth's frame order (see the module's docstring)."""
    gt_annos, gt_ids = gt
    det_annos, det_ids = det
    if all(gt_ids) and all(det_ids):
        by_id = {}
        for frame, anno in zip(det_ids, det_annos):
            if frame in by_id:
                raise ValueError(f"{det_source}: frame {frame} has two results")
            by_id[frame] = anno
        unknown = sorted(set(by_id) - set(gt_ids))
        if unknown:
            raise ValueError(f"{det_source}: {len(unknown)} result(s) of frames the ground truth "
                             f"does not have, e.g. {unknown[0]}")
        return [by_id.get(frame, empty_annos()) for frame in gt_ids]
    if len(det_annos) != len(gt_annos):
        raise ValueError(f"{det_source}: {len(det_annos)} frames of results for "
                         f"{len(gt_annos)} of ground truth, and no frame ids to match them by")
    return list(det_annos)


def folder_annos(root: Path, split: Optional[str], kind: str) -> Tuple[List[dict], List[str]]:
    """The label or detection files of a folder as annotation dicts, by frame id."""
    if kind == "label":
        folder = next((root / sub for sub in ("training/label_2", "label_2")
                       if (root / sub).is_dir()), root)
    else:
        folder = root / "data" if (root / "data").is_dir() else root
    if split:
        split_path = Path(split)
        if not split_path.is_file():
            split_path = root / "ImageSets" / f"{split}.txt"
        ids = [line.strip() for line in split_path.read_text().splitlines() if line.strip()]
    else:
        ids = sorted(p.stem for p in folder.glob("*.txt") if p.stem.isdigit())
    annos = []
    for frame in ids:
        path = folder / f"{frame}.txt"
        if kind == "detection" and not path.exists():
            annos.append(empty_annos())
        else:
            annos.append(stereodet.kitti.read_objects(path, kind))
    return annos, ids


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python3 -m stereodet", description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 1)[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    e = sub.add_parser("eval", help="evaluate OpenPCDet / mmdetection3d pickles or folders",
                       description=__doc__.split("\n\n")[0])
    e.add_argument("--gt", required=True, type=Path,
                   help="ground-truth infos pickle (list of dicts with 'annos') or label folder")
    e.add_argument("--det", required=True, type=Path,
                   help="results pickle (list of per-frame annotation dicts) or detection folder")
    e.add_argument("--split", help="with a label folder: frame ids (a file, or a name under "
                                   "ROOT/ImageSets)")
    e.add_argument("--classes", default="Car,Pedestrian,Cyclist", help="comma separated")
    e.add_argument("--metrics", default="2d,bev,3d", help="overlap kinds: 2d,bev,3d")
    e.add_argument("--difficulties", default="easy,moderate,hard")
    e.add_argument("--matcher", default="kitti", choices=["kitti", "optimal", "voc"])
    e.add_argument("--compat", default="devkit", choices=["devkit", "openpcdet"],
                   help="openpcdet: OpenPCDet's kitti_object_eval_python numbers")
    e.add_argument("--overlaps", default="strict", help="strict, loose, or strict,loose")
    e.add_argument("--records", action="store_true", help="with --out: also OUT/matches.csv")
    e.add_argument("--out", type=Path, help="write stereodet eval's results folder here")
    return parser


def _is_pickle(path: Path) -> bool:
    return path.is_file() and path.suffix in (".pkl", ".pickle")


def evaluate_command(args: argparse.Namespace) -> "stereodet.EvalResult":
    options = dict(classes=args.classes.split(","), metrics=args.metrics.split(","),
                   difficulties=args.difficulties.split(","), matcher=args.matcher,
                   compat=args.compat, overlaps=args.overlaps, records=args.records,
                   out=args.out)
    for path, flag in ((args.gt, "--gt"), (args.det, "--det")):
        if not path.exists():
            raise FileNotFoundError(f"{flag} {path}: no such file or folder")
    if not _is_pickle(args.gt) and not _is_pickle(args.det):
        return stereodet.evaluate(args.gt, args.det, split=args.split, **options)
    if _is_pickle(args.gt):
        if args.split:
            raise ValueError("--split is for a label folder; an infos pickle lists its frames")
        gt = gt_annos_from_infos(load_pickle(args.gt), str(args.gt))
    else:
        gt = folder_annos(args.gt, args.split, "label")
    if _is_pickle(args.det):
        det = det_annos_from_results(load_pickle(args.det), str(args.det))
    else:
        det = folder_annos(args.det, None, "detection")
    return stereodet.evaluate(gt[0], align(gt, det, str(args.det)), **options)


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        result = evaluate_command(args)
    except (ValueError, OSError, pickle.UnpicklingError) as error:
        if os.environ.get("STEREODET_DEBUG", "") not in ("", "0"):
            raise
        print(f"stereodet: error: {' '.join(str(error).split())}", file=sys.stderr)
        return 1
    print(result)
    if args.out is not None:
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
