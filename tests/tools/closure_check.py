#!/usr/bin/env python3
"""Loop closures against an outside matcher: for every closure that `robot-app slam` accepted
on a CARMEN corrected log, Open3D's ICP (a matcher nobody here wrote) aligns the closure's two
scans, started once from the reference poses' relative pose and once from the closure's own
measurement, and reports how far it lands from each. docs/slam.md quotes its figures.

Not run by the tests. Needs what `icp_floor.py` needs (`pip install open3d numpy`; on Debian
also `apt-get install libusb-1.0-0`). Run from the repository:

    robot-app -q slam --log ../shared/data/carmen/intel-corrected.log.gz --out /tmp/intel
    python3 tests/tools/closure_check.py intel /tmp/intel

Scan to scan only (no submap), so matches between two views of a place can fail: rows whose
fitness (share of points paired) is below --min-fit are left out of the medians.
"""
import argparse, json, math, pathlib, sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import numpy as np
import open3d as o3d
import icp_floor as floor

REG = o3d.pipelines.registration


def relative(a, b):
    """Pose b in the frame of pose a, as (x, y, yaw)."""
    m = np.linalg.inv(floor.se2(a)) @ floor.se2(b)
    return np.array([m[0, 2], m[1, 2], math.atan2(m[1, 0], m[0, 0])])


def apart(a, b):
    """Translation (m) and rotation (deg) between two relative poses."""
    d = relative(a, b)
    return math.hypot(d[0], d[1]), abs(math.degrees(d[2]))


def align(points, i, j, start, method, dist):
    """Open3D ICP of scan j onto scan i from `start`; the SE(2) result and its fitness."""
    target = floor.cloud(points[i], "2d" if method == "plane" else "none")
    source = floor.cloud(points[j], "none")
    est = (REG.TransformationEstimationPointToPlane() if method == "plane"
           else REG.TransformationEstimationPointToPoint())
    init = np.eye(4)
    t0 = floor.se2(start)
    init[:2, :2], init[:2, 3] = t0[:2, :2], t0[:2, 2]
    crit = REG.ICPConvergenceCriteria(1e-8, 1e-8, 100)
    res = REG.registration_icp(source, target, dist, init, est, crit)
    return floor.to_se2(np.asarray(res.transformation)), res.fitness


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("log", choices=sorted(floor.LOGS))
    ap.add_argument("slam_dir", help="the --out folder of robot-app slam on that log")
    ap.add_argument("--dist", type=float, default=0.3, help="correspondence distance, m")
    ap.add_argument("--min-fit", type=float, default=0.3)
    a = ap.parse_args()
    floor.ZS[:] = [-1.0, 0.0, 1.0]
    scans = floor.read_flaser(floor.LOGS[a.log])
    points = [floor.pts2d(r, 180.0) for r, _ in scans]
    report = json.load(open(pathlib.Path(a.slam_dir) / "slam.json"))
    # Closures name placed scans; they are the log's FLASER scans only when all were placed.
    if not report["placed"] == report["scans"] == len(scans):
        sys.exit(f"{a.slam_dir}: {report['placed']} of {report['scans']} scans placed, "
                 f"{len(scans)} FLASER lines: closure indices would not match")
    closures = report["loop_closure"]["closures"]
    runs = {(m, s): [] for m in ("point", "plane") for s in ("reference", "closure")}
    off = []
    for c in closures:
        if not c["accepted"]:
            continue
        i, j = c["from"], c["to"]
        ref = relative(scans[i][1], scans[j][1])
        m = c["measured"]
        ours = np.array([m["x_m"], m["y_m"], math.radians(m["heading_deg"])])
        t, r = apart(ref, ours)
        row = {"from": i, "to": j, "off_m": t, "off_deg": r}
        for (method, start), out in runs.items():
            q, fit = align(points, i, j, ref if start == "reference" else ours, method, a.dist)
            out.append((*apart(q, ref), *apart(q, ours), fit))
            row[(method, start)] = out[-1]
        if t > 0.2 or r > 2.0:
            off.append(row)
    n = len(next(iter(runs.values())))
    print(f"open3d {o3d.__version__}; {a.log}: {n} accepted closures, {len(off)} more than "
          f"0.2 m or 2 deg from the reference; correspondence distance {a.dist} m")
    print("ICP, started from | fit >= min | median to the reference (m, deg) | median to the closure (m, deg)")
    for (method, start), out in runs.items():
        v = np.array([o for o in out if o[4] >= a.min_fit])
        print(f"point-to-{method:5s}, {start:9s} | {len(v):4d} | {np.median(v[:, 0]):.3f} m "
              f"{np.median(v[:, 1]):.2f} deg | {np.median(v[:, 2]):.3f} m {np.median(v[:, 3]):.2f} deg")
    for row in off:
        print(f"closure {row['from']} -> {row['to']}: {row['off_m']:.3f} m {row['off_deg']:.2f} deg "
              "from the reference; point-to-plane from the reference lands "
              "{:.3f} m {:.2f} deg from it, {:.3f} m {:.2f} deg from the closure (fit {:.2f})"
              .format(*row[("plane", "reference")]))


if __name__ == "__main__":
    main()
