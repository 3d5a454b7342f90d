"""Prints evo's figures for two TUM trajectories as JSON: RPE over every relation k -> k+1 and k -> k+10
(translation in m, rotation in deg: mean and std) and APE after an SE(3) alignment (rmse, mean).

Usage: python3 evo_figures.py REFERENCE.tum ESTIMATE.tum
"""
import copy
import json
import sys

from evo.core import metrics, sync
from evo.tools import file_interface


def main() -> None:
    ref = file_interface.read_tum_trajectory_file(sys.argv[1])
    est = file_interface.read_tum_trajectory_file(sys.argv[2])
    ref, est = sync.associate_trajectories(ref, est)
    out = {}
    for delta in (1, 10):
        for name, relation in (
            ("trans", metrics.PoseRelation.translation_part),
            ("rot", metrics.PoseRelation.rotation_angle_deg),
        ):
            rpe = metrics.RPE(relation, delta=delta, delta_unit=metrics.Unit.frames, all_pairs=True)
            rpe.process_data((ref, est))
            out[f"rpe{delta}_{name}_mean"] = rpe.get_statistic(metrics.StatisticsType.mean)
            out[f"rpe{delta}_{name}_std"] = rpe.get_statistic(metrics.StatisticsType.std)
    aligned = copy.deepcopy(est)
    aligned.align(ref, correct_scale=False)
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, aligned))
    out["ape_rmse"] = ape.get_statistic(metrics.StatisticsType.rmse)
    out["ape_mean"] = ape.get_statistic(metrics.StatisticsType.mean)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
