#!/usr/bin/env python3
"""The front end's relation errors k -> k+1 beside an outside matcher's, relation by relation:
Open3D's point-to-plane ICP (a matcher nobody here wrote) aligns every consecutive pair of
FLASER scans of a CARMEN corrected log, started from the reference poses' relative pose, and
lands some distance from it; `robot-app slam` lands some distance from the same reference.
Grouping the relations by how far Open3D lands shows where the front end loses to scan
matching from a perfect guess and where the reference is not what the laser sees (long
corridors: both land far from it). docs/slam.md quotes its figures.

Not run by the tests. Needs what `icp_floor.py` needs (`pip install open3d numpy`; on Debian
also `apt-get install libusb-1.0-0`). Run from the repository:

    robot-app -q slam --log ../shared/data/carmen/aces-corrected.log.gz --no-loop-closure --out /tmp/aces
    python3 tests/tools/relation_check.py aces /tmp/aces [--start slam]

`--start slam` starts Open3D from the front end's own relative pose instead: where the scans
pin the relation, it lands near the reference from either start.

The slam output must hold one TUM line per scan of the log (every scan placed), with
`reference.tum` beside `trajectory.tum`.
"""
import argparse, math, pathlib, sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import numpy as np
import open3d as o3d
import icp_floor as floor

REG = o3d.pipelines.registration
BINS = [0.0, 0.03, 0.06, 0.1, 0.2, math.inf]


def tum(path):
    """(x, y, yaw) of every line of a TUM file."""
    a = np.loadtxt(path, ndmin=2)
    return np.c_[a[:, 1], a[:, 2], 2 * np.arctan2(a[:, 6], a[:, 7])]


def step_error(poses, ref, k):
    """Translation error (m) of the relation k -> k+1 of `poses` against `ref`."""
    e = np.linalg.inv(np.linalg.inv(floor.se2(ref[k])) @ floor.se2(ref[k + 1])) @ (
        np.linalg.inv(floor.se2(poses[k])) @ floor.se2(poses[k + 1]))
    return math.hypot(e[0, 2], e[1, 2])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("log", choices=sorted(floor.LOGS))
    ap.add_argument("slam_dir", type=pathlib.Path)
    ap.add_argument("--dist", type=float, default=0.2, help="correspondence distance, m")
    ap.add_argument("--min-fit", type=float, default=0.3)
    ap.add_argument("--start", choices=["reference", "slam"], default="reference",
                    help="start Open3D from the reference's relative pose or from slam's")
    a = ap.parse_args()
    floor.ZS[:] = [-1.0, 0.0, 1.0]
    scans = floor.read_flaser(floor.LOGS[a.log])
    for f in ("trajectory.tum", "reference.tum"):
        if not (a.slam_dir / f).exists():
            sys.exit(f"{a.slam_dir / f} not found: run robot-app slam on the log first")
    est = tum(a.slam_dir / "trajectory.tum")
    ref = tum(a.slam_dir / "reference.tum")
    if len(est) != len(scans) or len(ref) != len(scans):
        sys.exit(f"{len(scans)} scans in the log, {len(est)} in trajectory.tum and {len(ref)} "
                 f"in reference.tum: every scan must be placed")
    crit = REG.ICPConvergenceCriteria(1e-8, 1e-8, 100)
    method = REG.TransformationEstimationPointToPlane()
    rows = []
    for k in range(len(scans) - 1):
        r = np.linalg.inv(floor.se2(scans[k][1])) @ floor.se2(scans[k + 1][1])
        s0 = r if a.start == "reference" else np.linalg.inv(floor.se2(est[k])) @ floor.se2(est[k + 1])
        init = np.eye(4)
        init[:2, :2], init[:2, 3] = s0[:2, :2], s0[:2, 2]
        tgt = floor.cloud(floor.pts2d(scans[k][0], 180.0), "2d")
        src = floor.cloud(floor.pts2d(scans[k + 1][0], 180.0), "none")
        res = REG.registration_icp(src, tgt, a.dist, init, method, crit)
        T = np.asarray(res.transformation)
        if not np.all(np.isfinite(T)) or res.fitness < a.min_fit:
            continue
        e = np.linalg.inv(r) @ floor.se2(floor.to_se2(T))
        rows.append((math.hypot(e[0, 2], e[1, 2]), step_error(est, ref, k), k))
    if not rows:
        sys.exit("Open3D paired no relation; try a lower --min-fit")
    o, s = np.array([x[0] for x in rows]), np.array([x[1] for x in rows])
    print(f"open3d {o3d.__version__}; {a.log}: {len(rows)} of {len(scans) - 1} relations "
          f"paired (fitness >= {a.min_fit}), Open3D started from the {a.start}'s relative "
          f"pose; mean error against the reference: "
          f"slam {s.mean():.4f} m, open3d {o.mean():.4f} m")
    print("open3d lands      relations  slam mean  open3d mean")
    for lo, hi in zip(BINS, BINS[1:]):
        m = (o >= lo) & (o < hi)
        if m.any():
            print(f"{lo:5.2f}-{hi:<5.2f} m    {m.sum():9d}  {s[m].mean():9.4f}  {o[m].mean():11.4f}")
    worst = sorted((x for x in rows if x[0] < 0.1), key=lambda x: -x[1])[:8]
    print("largest slam errors where open3d lands within 0.1 m (relation k -> k+1: slam, open3d):",
          ", ".join(f"{k}: {sv:.3f}, {ov:.3f}" for ov, sv, k in worst))


if __name__ == "__main__":
    main()
