//! A base that does not do what it is told: the laser, not the commands, decides where the
//! robot is. A stalled base must never look like an arrival, and slip or short turns must not
//! make the robot claim a target it is far from.

use navigator::{Navigator, NoMonitor, Outcome, Params, Reason};
use scan_types::Pose2;
use sim_laser::{BaseGains, SensorPreset, SimSetup, TruthHandle, paper_start, paper_target};

fn run_with(gains: BaseGains, seed: u64) -> (Outcome, TruthHandle) {
    let params = Params::goalseek();
    // The paper's scenario: its world, laser and noise, a 0.3 m robot (goalseek's radius).
    let sim = SimSetup::paper(seed)
        .build()
        .expect("the paper's setup builds")
        .with_base_gains(gains);
    let (mut laser, mut base, truth) = sim.split();
    let geometry = SensorPreset::Paper.geometry();
    let nav = Navigator::new(params, geometry, paper_start(), paper_target()).unwrap();
    let outcome = navigator::run(nav, &mut laser, &mut base, &mut NoMonitor);
    (outcome, truth)
}

fn true_distance_to_target(truth: &TruthHandle) -> f64 {
    let p: Pose2 = truth.pose();
    p.position().distance_m(&paper_target())
}

#[test]
fn a_stalled_base_is_reported_as_stalled_not_as_an_arrival() {
    for seed in [0, 7] {
        let (outcome, truth) = run_with(
            BaseGains {
                drive: 0.0,
                turn: 1.0,
            },
            seed,
        );
        assert_eq!(
            outcome.reason,
            Reason::BaseStalled,
            "seed {seed}: {}",
            outcome.note
        );
        // The robot never moved from the start: the estimate says so too (within the
        // scan matcher's noise), and it does not sit at the target.
        let start = paper_start().position();
        assert_eq!(truth.travelled_m(), 0.0);
        assert!(
            outcome.estimate.position().distance_m(&start) < 0.15,
            "seed {seed}: estimate {:?}",
            outcome.estimate
        );
    }
}

#[test]
fn slip_and_short_turns_give_no_false_arrival() {
    // 50 % wheel slip, then turns 20 % short: a run may fail, but when it says "reached" the
    // robot is truly there (the goal tolerance, 0.15 m, plus 0.1 m of localisation error).
    let faults = [
        BaseGains {
            drive: 0.5,
            turn: 1.0,
        },
        BaseGains {
            drive: 1.0,
            turn: 0.8,
        },
    ];
    for gains in faults {
        for seed in [0, 7, 23] {
            let (outcome, truth) = run_with(gains, seed);
            let d = true_distance_to_target(&truth);
            if outcome.reason == Reason::Reached {
                assert!(
                    d < 0.25,
                    "{gains:?} seed {seed}: reached, but {d:.3} m away"
                );
            }
            assert_eq!(truth.collisions(), 0, "{gains:?} seed {seed}");
        }
    }
}
