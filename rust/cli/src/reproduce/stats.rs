//! Statistics of `sixaxis reproduce` over typed runs: means and standard deviations over
//! seeds, and the per-condition figures of `reproduction.json` ([`ConditionStats`]).

use serde::Serialize;
use sixaxis_core::qlearning::TrainReport;

/// Mean of `xs`; NaN for none (written as `null` in JSON, `—` in the report).
pub fn mean(xs: &[f64]) -> f64 {
    if xs.is_empty() {
        f64::NAN
    } else {
        xs.iter().sum::<f64>() / xs.len() as f64
    }
}

/// Sample standard deviation of `xs` (divisor n - 1); 0 for fewer than two.
pub fn std_dev(xs: &[f64]) -> f64 {
    if xs.len() < 2 {
        return 0.0;
    }
    let m = mean(xs);
    (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (xs.len() - 1) as f64).sqrt()
}

/// Mean of `x` over the values that exist.
fn mean_of<T: Into<f64> + Copy>(xs: impl Iterator<Item = Option<T>>) -> f64 {
    mean(&xs.flatten().map(Into::into).collect::<Vec<f64>>())
}

/// Mean steps of each episode over the runs' curves: episode `k`'s sum over the runs that
/// have one, divided by the number of runs; as long as the first curve.
pub fn mean_curve(curves: &[&[u32]]) -> Vec<f64> {
    let Some(first) = curves.first() else {
        return Vec::new();
    };
    let mut sum = vec![0.0; first.len()];
    for c in curves {
        for (acc, &n) in sum.iter_mut().zip(c.iter()) {
            *acc += n as f64;
        }
    }
    let n = curves.len() as f64;
    sum.iter().map(|x| x / n).collect()
}

/// What one learning condition (assisted or not) gives over its seeds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConditionStats {
    /// Runs whose learned path reaches the target.
    pub reached: usize,
    /// Mean wall time of a run, s.
    pub wall_time_s_mean: f64,
    /// Standard deviation of the wall time, s.
    pub wall_time_s_std: f64,
    /// Mean environment steps of a run.
    pub total_steps_mean: f64,
    /// Mean moves of the learned paths (runs that reach the target).
    pub path_length_mean: f64,
    /// Mean converged episode (runs with one).
    pub converged_episode_mean: f64,
    /// Mean episode from which the path length stays (runs with one).
    pub length_converged_episode_mean: f64,
    /// Mean steps of each episode ([`mean_curve`]).
    pub mean_steps_per_episode: Vec<f64>,
}

impl ConditionStats {
    /// The statistics of `runs`, with `curves` the steps per episode of each run.
    pub fn new(runs: &[TrainReport], curves: &[&[u32]]) -> Self {
        let times: Vec<f64> = runs.iter().map(|r| r.wall_time_s).collect();
        let steps: Vec<f64> = runs.iter().map(|r| r.total_steps as f64).collect();
        ConditionStats {
            reached: runs.iter().filter(|r| r.reached).count(),
            wall_time_s_mean: mean(&times),
            wall_time_s_std: std_dev(&times),
            total_steps_mean: mean(&steps),
            path_length_mean: mean_of(runs.iter().map(|r| r.path_length.map(|n| n as f64))),
            converged_episode_mean: mean_of(runs.iter().map(|r| r.converged_episode)),
            length_converged_episode_mean: mean_of(runs.iter().map(|r| r.length_converged_episode)),
            mean_steps_per_episode: mean_curve(curves),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_sample_std_dev() {
        assert_eq!(mean(&[1.0, 2.0, 6.0]), 3.0);
        assert!(mean(&[]).is_nan());
        // Sample variance of 1, 2, 6: (4 + 1 + 9) / 2 = 7.
        assert!((std_dev(&[1.0, 2.0, 6.0]) - 7f64.sqrt()).abs() < 1e-12);
        assert_eq!(std_dev(&[5.0]), 0.0);
    }

    #[test]
    fn mean_curve_divides_by_the_runs_and_keeps_the_first_length() {
        assert_eq!(mean_curve(&[&[2, 4, 6], &[4, 4, 0]]), [3.0, 4.0, 3.0]);
        // A shorter second run adds only where it has episodes.
        assert_eq!(mean_curve(&[&[2, 4], &[4]]), [3.0, 2.0]);
        assert!(mean_curve(&[]).is_empty());
    }
}
