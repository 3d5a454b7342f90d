#!/usr/bin/env python3
"""The noise floor of the relations k -> k+1 of the CARMEN corrected logs: Open3D's ICP (a
matcher nobody here wrote) started from the reference relative pose of every consecutive pair
of FLASER scans, and how far it lands from it. docs/slam.md quotes its figures.

Not run by the tests. Needs `pip install open3d numpy` (Open3D 0.20.0 was used; on Debian it
also needs `apt-get install libusb-1.0-0`). Run from the repository:

    python3 tests/tools/icp_floor.py --zs=-1,0,1 --dists 0.2

Each 2D scan becomes vertical walls (its points copied at the heights --zs); the ICP result is
projected back onto SE(2) (x, y, yaw). Rows "nrm=kd" use Open3D's own normals, which come out
vertical with layers 1 m apart: ignore them there (their error reads 0).
"""
import argparse, gzip, math, pathlib
import numpy as np
import open3d as o3d

DATA = pathlib.Path(__file__).resolve().parents[2].parent / "shared" / "data" / "carmen"
LOGS = {"intel": DATA / "intel-corrected.log.gz",
        "aces": DATA / "aces-corrected.log.gz"}
ZS = [-0.2, 0.0, 0.2]

def read_flaser(path):
    scans = []
    with gzip.open(path, "rt") as f:
        for line in f:
            if not line.startswith("FLASER"):
                continue
            t = line.split()
            n = int(t[1])
            r = np.array(t[2:2 + n], float)
            x, y, th = map(float, t[2 + n:5 + n])
            scans.append((r, np.array([x, y, th])))
    return scans

def se2(p):
    c, s = math.cos(p[2]), math.sin(p[2])
    return np.array([[c, -s, p[0]], [s, c, p[1]], [0, 0, 1.0]])

def pts2d(r, spread):
    n = len(r)
    ang = -math.pi / 2 + np.arange(n) * math.pi / spread   # spread=180 -> 1 deg steps (MANIFEST)
    ok = (r > 0) & (r < 50)
    return np.c_[r[ok] * np.cos(ang[ok]), r[ok] * np.sin(ang[ok])]

def normals2d(p, k=5, rmax=0.5):
    """Normal in the scan plane from PCA of up to k nearest 2D neighbours within rmax (else 0)."""
    d = np.linalg.norm(p[:, None] - p[None], axis=2)
    out = np.zeros((len(p), 2))
    for i in range(len(p)):
        idx = np.argsort(d[i])[:k + 1]
        idx = idx[d[i, idx] < rmax]
        if len(idx) < 3:
            continue
        q = p[idx] - p[idx].mean(0)
        w, v = np.linalg.eigh(q.T @ q)
        nrm = v[:, 0]
        if nrm @ p[i] > 0:      # orient toward the sensor
            nrm = -nrm
        out[i] = nrm
    return out

def cloud(p2, mode):
    P = np.vstack([np.c_[p2, np.full(len(p2), z)] for z in ZS])
    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(P))
    if mode == "2d":
        n2 = normals2d(p2)
        good = np.linalg.norm(n2, axis=1) > 0
        N = np.vstack([np.c_[n2, np.zeros(len(n2))]] * len(ZS))
        keep = np.tile(good, len(ZS))
        pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(P[keep]))
        pc.normals = o3d.utility.Vector3dVector(N[keep])
    elif mode == "kd":
        pc.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=0.5, max_nn=30))
        pc.orient_normals_towards_camera_location(np.zeros(3))
    return pc

def to_se2(T):
    """Project 4x4 onto SE(2): keep t_x, t_y and yaw = atan2(R10, R00); drop z, roll, pitch."""
    return np.array([T[0, 3], T[1, 3], math.atan2(T[1, 0], T[0, 0])])

def run(name, scans, spread, method, dist, nmode, min_fit):
    clouds_t, clouds_s = {}, {}
    est = (o3d.pipelines.registration.TransformationEstimationPointToPlane() if method == "plane"
           else o3d.pipelines.registration.TransformationEstimationPointToPoint())
    crit = o3d.pipelines.registration.ICPConvergenceCriteria(1e-8, 1e-8, 100)
    P2 = [pts2d(r, spread) for r, _ in scans]
    et, er, fits, extra = [], [], [], []
    nbad = 0
    for k in range(len(scans) - 1):
        ref = np.linalg.inv(se2(scans[k][1])) @ se2(scans[k + 1][1])
        init = np.eye(4); init[:2, :2] = ref[:2, :2]; init[:2, 3] = ref[:2, 2]
        tgt = cloud(P2[k], nmode if method == "plane" else "none")
        src = cloud(P2[k + 1], "none")
        res = o3d.pipelines.registration.registration_icp(src, tgt, dist, init, est, crit)
        T = np.asarray(res.transformation)
        if not np.all(np.isfinite(T)) or res.fitness < min_fit:
            nbad += 1
            continue
        q = to_se2(T)
        E = np.linalg.inv(ref) @ se2(q)
        et.append(math.hypot(E[0, 2], E[1, 2]))
        er.append(abs(math.degrees(math.atan2(E[1, 0], E[0, 0]))))
        fits.append(res.fitness)
        roll_pitch = math.degrees(math.acos(max(-1, min(1, T[2, 2]))))
        extra.append((abs(T[2, 3]), roll_pitch))
    et, er, ex = np.array(et), np.array(er), np.array(extra)
    n = len(scans) - 1
    print(f"{name:5s} {method:5s} d={dist:.2f} nrm={nmode if method=='plane' else '-':4s} "
          f"ok {len(et):4d}/{n} | |t| mean {et.mean():.4f} med {np.median(et):.4f} "
          f"p90 {np.percentile(et,90):.4f} m | rot mean {er.mean():.3f} med {np.median(er):.3f} deg"
          f" | fit med {np.median(fits):.2f} | |z| max {ex[:,0].max():.3g} tilt max {ex[:,1].max():.3g} deg"
          f" tilt>1deg {int((ex[:,1]>1).sum())}",
          flush=True)

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spread", type=float, default=180.0)
    ap.add_argument("--dists", default="0.2,0.3")
    ap.add_argument("--min-fit", type=float, default=0.3)
    ap.add_argument("--logs", default="intel,aces")
    ap.add_argument("--zs", default="-0.2,0,0.2", help="z layers of the vertical-wall embedding")
    a = ap.parse_args()
    ZS[:] = [float(z) for z in a.zs.split(",")]
    print(f"open3d {o3d.__version__}; beam i at -90 + i*180/{a.spread:g} deg; ranges kept 0<r<50 m; "
          f"ok = finite and fitness >= {a.min_fit}; z layers {ZS}", flush=True)
    for name in a.logs.split(","):
        scans = read_flaser(LOGS[name])
        for d in map(float, a.dists.split(",")):
            for method, nm in (("plane", "2d"), ("plane", "kd"), ("point", "none")):
                run(name, scans, a.spread, method, d, nm, a.min_fit)

if __name__ == "__main__":
    main()
