//! Generalised advantage estimation on plain vectors.

/// How an episode ended: at a terminal state (the future is worth 0) or cut by the time limit (the future is worth
/// what the value function says about the last observation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EpisodeEnd {
    Terminal,
    Truncated { bootstrap_value: f32 },
}

/// Advantages `A_t = sum_k (gamma lambda)^k delta_{t+k}` with `delta_t = r_t + gamma V_{t+1} - V_t`, and value
/// targets `A_t + V_t`, for one episode.
pub fn gae(
    rewards: &[f32],
    values: &[f32],
    end: EpisodeEnd,
    gamma: f32,
    lambda: f32,
) -> (Vec<f32>, Vec<f32>) {
    assert_eq!(rewards.len(), values.len());
    let n = rewards.len();
    let mut adv = vec![0.0; n];
    let mut next_value = match end {
        EpisodeEnd::Terminal => 0.0,
        EpisodeEnd::Truncated { bootstrap_value } => bootstrap_value,
    };
    let mut running = 0.0;
    for t in (0..n).rev() {
        let delta = rewards[t] + gamma * next_value - values[t];
        running = delta + gamma * lambda * running;
        adv[t] = running;
        next_value = values[t];
    }
    let targets = adv.iter().zip(values).map(|(a, v)| a + v).collect();
    (adv, targets)
}

/// Shifts and scales advantages to mean 0 and standard deviation 1 (over the whole batch).
pub fn standardize(adv: &mut [f32]) {
    if adv.is_empty() {
        return;
    }
    let n = adv.len() as f64;
    let mean = adv.iter().map(|&a| a as f64).sum::<f64>() / n;
    let var = adv.iter().map(|&a| (a as f64 - mean).powi(2)).sum::<f64>() / n;
    let std = var.sqrt().max(1e-4);
    for a in adv.iter_mut() {
        *a = ((*a as f64 - mean) / std) as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terminal_episode_by_hand() {
        // gamma 0.9, lambda 0.5. r = [1, 2], V = [0.5, 1.0], terminal.
        // delta_1 = 2 + 0 - 1 = 1; A_1 = 1.
        // delta_0 = 1 + 0.9*1.0 - 0.5 = 1.4; A_0 = 1.4 + 0.45*1 = 1.85.
        let (a, t) = gae(&[1.0, 2.0], &[0.5, 1.0], EpisodeEnd::Terminal, 0.9, 0.5);
        assert!(
            (a[0] - 1.85).abs() < 1e-6 && (a[1] - 1.0).abs() < 1e-6,
            "{a:?}"
        );
        assert!(
            (t[0] - 2.35).abs() < 1e-6 && (t[1] - 2.0).abs() < 1e-6,
            "{t:?}"
        );
    }

    #[test]
    fn truncated_episode_bootstraps() {
        // Same, but cut by the time limit with V(s_T) = 3: delta_1 = 2 + 2.7 - 1 = 3.7; A_0 = 1.4 + 0.45*3.7.
        let (a, _) = gae(
            &[1.0, 2.0],
            &[0.5, 1.0],
            EpisodeEnd::Truncated {
                bootstrap_value: 3.0,
            },
            0.9,
            0.5,
        );
        assert!((a[1] - 3.7).abs() < 1e-6, "{a:?}");
        assert!((a[0] - (1.4 + 0.45 * 3.7)).abs() < 1e-6, "{a:?}");
    }

    #[test]
    fn lambda_one_gives_discounted_return_minus_value() {
        let r = [1.0, 0.0, 2.0, -1.0];
        let v = [0.3, 0.1, -0.2, 0.4];
        let (a, t) = gae(&r, &v, EpisodeEnd::Terminal, 0.95, 1.0);
        let ret0 = 1.0 + 0.95 * 0.0 + 0.95f32.powi(2) * 2.0 - 0.95f32.powi(3);
        assert!((t[0] - ret0).abs() < 1e-5 && (a[0] - (ret0 - 0.3)).abs() < 1e-5);
    }

    #[test]
    fn standardize_gives_zero_mean_unit_std() {
        let mut a = vec![1.0, 2.0, 3.0, 6.0];
        standardize(&mut a);
        let m: f32 = a.iter().sum::<f32>() / 4.0;
        let v: f32 = a.iter().map(|x| (x - m).powi(2)).sum::<f32>() / 4.0;
        assert!(m.abs() < 1e-6 && (v - 1.0).abs() < 1e-5);
    }
}
