"""Talks to a SCIP 2.0 sensor over TCP with the third-party driver hokuyolx (PyPI) and prints
what it read as one JSON object: parameters (PP), version (VV), state (II), sensor times from
time-adjust mode (TM0, TM1 x 3, TM2), the angles hokuyolx computes, two single scans (GD) and a
counted stream of five scans (MD).

Usage: python3 hokuyolx_client.py HOST PORT

hokuyolx's own time synchronisation and its laser-state query use `%ST`, a SCIP 2.2 command,
so they are left off (tsync=False); raw sensor times are kept (convert_time=False).
"""
import json
import sys

from hokuyolx import HokuyoLX


def ints(values):
    return [int(v) for v in values]


def main() -> None:
    host, port = sys.argv[1], int(sys.argv[2])
    # Connects, reads PP (info=True) and switches the laser on with BM (activate=True).
    laser = HokuyoLX(addr=(host, port), tsync=False, convert_time=False, timeout=5)
    out = {
        "params": laser.sensor_parameters(),
        "version": laser.version(),
        "state": laser.sensor_state(),
        "model": laser.model,
        "scan_freq": laser.scan_freq,
    }
    laser.tsync_enter()
    out["tm1_ms"] = [int(laser.tsync_get()) for _ in range(3)]
    laser.tsync_exit()
    laser.activate()
    angles = laser.get_angles()
    out["angle_count"] = len(angles)
    out["angles_rad"] = [float(angles[0]), float(angles[540]), float(angles[-1])]
    singles = []
    for _ in range(2):
        ts, scan = laser.get_dist()
        singles.append({"timestamp_ms": int(ts), "ranges_mm": ints(scan)})
    out["single"] = singles
    stream = []
    for scan, ts, pending in laser.iter_dist(scans=5):
        stream.append({"timestamp_ms": int(ts), "pending": int(pending), "ranges_mm": ints(scan)})
    out["stream"] = stream
    laser.close()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
