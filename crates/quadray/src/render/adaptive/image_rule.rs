//! The image rule's allocation: which pixels the next round doubles so that the image's mean
//! squared error falls the most for the work spent.
//!
//! A pixel i with nᵢ samples has an estimated squared error sᵢ (its share of the image's MSE:
//! [`crate::film::PixelEstimate::squared_error`] corrected by the calibration) and costs cᵢ rays a
//! sample. Its error falls as n^−α (α from the calibration: 1 for independent samples, more under
//! stratification), so at nᵢ' samples it is sᵢ (nᵢ/nᵢ')^α. With every sᵢ known, the counts that
//! minimise the image's summed error for a given work Σ cᵢ nᵢ' satisfy
//! α sᵢ nᵢ^α nᵢ'^(−α−1) = λ' cᵢ (Lagrange), that is nᵢ'(λ) = nᵢ (sᵢ/(nᵢ cᵢ λ))^(1/(1+α)): for
//! α = 1, nᵢ' ∝ σᵢ/√cᵢ.
//!
//! The sᵢ are estimates from a few samples, though, and the rule that ranks pixels by
//! sᵢ/(nᵢ cᵢ), the optimum's, starves refined pixels whose estimate came out low. Ranked by
//! vᵢ = sᵢ/cᵢ instead (each round doubles the pixels whose squared error per ray is above one
//! threshold), the same work reached lower errors: on defense (480x270, one thread, target
//! 0.0007) 6.0e-4 in 1.95 s against 7.1e-4 in 1.78 s; on reflective 6.1e-4 in 2.97 s against
//! 6.6e-4 in 3.55 s. The model above still predicts the error a threshold reaches: a pixel above
//! it is taken to the count where its value falls to it, nᵢ' = nᵢ (vᵢ/λ)^(1/α) at most
//! 2^[`MAX_DOUBLINGS`] times its count, which this round doubles when nᵢ' ≥ √2 nᵢ (the geometric
//! midpoint of keeping and doubling). λ is chosen each round from the latest estimates so that
//! the predicted MSE meets the target; with a budget, it is at least the least λ whose whole
//! allocation (every pixel taken to nᵢ') the budget left pays for, and the round never costs
//! more than that budget.

/// One pixel as the allocation sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct PixelState {
    /// Samples taken.
    pub count: u32,
    /// Estimated squared error of its display values (its share of the image's MSE).
    pub squared_error: f64,
    /// Rays a sample of it costs (at least 1).
    pub cost: f64,
}

impl PixelState {
    /// What refining the pixel is worth per ray: its squared error over its cost, s / c (see the
    /// module documentation for why not s / (n c)).
    pub fn value(&self) -> f64 {
        self.squared_error / self.cost
    }
}

/// What is left to spend, and in which unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Budget {
    /// Samples (a sample budget: the same on any machine).
    Samples(f64),
    /// Rays (a time limit, converted by the rays a second traced so far).
    Rays(f64),
}

/// What the next round aims for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Aim {
    /// The image MSE to reach (none: spend the budget, or go on to the maximum count).
    pub target_mse: Option<f64>,
    /// What is left to spend, if there is a budget.
    pub budget: Option<Budget>,
    /// Samples no pixel exceeds.
    pub max_spp: u32,
    /// The exponent of the error's fall with the sample count (see the module documentation).
    pub alpha: f64,
}

/// The estimated MSE of the pixels: the mean of their squared errors.
pub(super) fn mean_squared_error(states: &[PixelState]) -> f64 {
    states.iter().map(|s| s.squared_error).sum::<f64>() / states.len().max(1) as f64
}

/// How many times a round may double a pixel's samples at most: once. Measured on defense
/// (480x270, one thread, target 0.0007 and 0.00125): letting a round jump to the power of two
/// nearest the optimum, up to 8×, took the true error from 7.1e-4 to 1.0e-3 for 10% fewer
/// samples: the jumps follow one noisy estimate too far, and the neighbour rounds end sooner.
pub(super) const MAX_DOUBLINGS: u32 = 1;

/// One round's decision: the pixels whose optimum is above their count are brought towards it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Step {
    /// The Lagrange multiplier λ of the optimum.
    pub lambda: f64,
    /// The exponent of the error's fall the optimum was computed with.
    pub alpha: f64,
    /// Whether a count below its optimum is rounded up to the next power of two (when no
    /// pixel's optimum is √2 times its count or more, so that rounding to the nearest would
    /// refine nothing) rather than to the nearest.
    pub round_up: bool,
}

impl Step {
    /// The count the round brings a pixel of `state` to: its count times the power of two
    /// nearest the count it is taken to (or the next above, with `round_up`), at most
    /// 2^[`MAX_DOUBLINGS`] times its count and `max_spp`; its own count when it is not refined.
    pub fn target(&self, state: &PixelState, max_spp: u32) -> u32 {
        let value = state.value();
        if state.count >= max_spp || value.is_nan() || value <= self.lambda {
            return state.count;
        }
        // log₂ of the ratio of the count it is taken to to its count: (1/α) log₂(v/λ).
        let doublings = (value / self.lambda).log2() / self.alpha;
        let doublings = if self.round_up {
            doublings.ceil()
        } else {
            doublings.round()
        };
        let doublings = (doublings.max(0.0) as u32).min(MAX_DOUBLINGS);
        (state.count << doublings).min(max_spp)
    }
}

/// The next round's step, or `None` when sampling should stop: the target is met, the budget
/// left cannot pay for a round that refines anything, or no pixel can improve.
pub(super) fn next_step(states: &[PixelState], aim: &Aim) -> Option<Step> {
    let open = |s: &&PixelState| s.count < aim.max_spp && s.value() > 0.0;
    let highest = states
        .iter()
        .filter(open)
        .map(PixelState::value)
        .fold(0.0, f64::max);
    if highest <= 0.0 || !highest.is_finite() {
        return None;
    }
    if let Some(target) = aim.target_mse
        && mean_squared_error(states) <= target
    {
        return None;
    }
    // The error of pixels at the maximum count stays; the others are predicted as if their
    // counts could rise without bound, so that a target beyond the maximum still ranks them
    // (a λ of 0 would double every pixel with any error, a flat pixel's mean error included).
    // Where the pixels at the maximum alone exceed the target, the others aim a quarter of it
    // lower than they stand.
    let lambda = aim.target_mse.map_or(0.0, |target| {
        let at_max = states.iter().filter(|s| s.count >= aim.max_spp);
        let floor = at_max.map(|s| s.squared_error).sum::<f64>() / states.len().max(1) as f64;
        let goal = target.max(floor + 0.25 * target);
        let prediction = Prediction::new(states, aim);
        solve(highest, |l| prediction.mse(l) > goal)
    });
    let step = |lambda: f64| {
        // Round to the nearest power of two where some pixel is taken to √2 times its count or
        // more; where none is, every pixel's count lies between keeping and doubling, and
        // rounding up moves towards it.
        let midpoint = 2f64.powf(aim.alpha / 2.0) * lambda;
        Step {
            lambda: lambda.min(highest * (1.0 - 1e-12)),
            alpha: aim.alpha,
            round_up: highest <= midpoint,
        }
    };
    let Some(budget) = aim.budget else {
        return Some(step(lambda));
    };
    // What the round of a λ costs in the budget's unit.
    let work = |lambda: f64| {
        let step = step(lambda);
        states
            .iter()
            .map(|s| budget.per_sample(s) * (step.target(s, aim.max_spp) - s.count) as f64)
            .sum::<f64>()
    };
    let left = budget.amount();
    // The budget pays for a whole plan, not one round: the smallest λ at or above the target's
    // whose optimal counts, every pixel brought to where its value meets λ, the budget left pays
    // for. Spending it all on the next round instead doubled nearly every pixel under a time
    // limit (defense, 0.8 s at 480x270: 16 to 32 spp everywhere, uniform sampling's image).
    // n' = n (v/λ)^(1/α): each open pixel's n v^(1/α) once, so that a λ costs a multiply a pixel
    // (a power a pixel in each of the bisection's steps made a 0.1 s time limit on defense take
    // 0.51 s where the first round alone takes 0.43 s).
    let open_pixels: Vec<(f64, f64, f64, f64)> = states
        .iter()
        .filter(open)
        .map(|s| {
            let n = s.count as f64;
            let scale = n * s.value().powf(1.0 / aim.alpha);
            (s.value(), scale, n, budget.per_sample(s))
        })
        .collect();
    let max = aim.max_spp as f64;
    let planned = |l: f64| {
        let shrink = l.powf(-1.0 / aim.alpha);
        (open_pixels.iter())
            .filter(|p| p.0 > l)
            .map(|&(_, scale, n, cost)| cost * ((scale * shrink).min(max) - n).max(0.0))
            .sum::<f64>()
    };
    let lambda = solve(highest, |l| l >= lambda && planned(l) <= left);
    if work(lambda) <= left {
        return (work(lambda) > 0.0).then(|| step(lambda));
    }
    let fitted = solve(highest, |l| l >= lambda && work(l) <= left);
    let spent = work(fitted);
    (spent > 0.0 && spent <= left).then(|| step(fitted))
}

impl Budget {
    /// The amount left, in its unit.
    fn amount(self) -> f64 {
        match self {
            Budget::Samples(n) | Budget::Rays(n) => n,
        }
    }

    /// What one sample of `state` costs in this budget's unit.
    fn per_sample(self, state: &PixelState) -> f64 {
        match self {
            Budget::Samples(_) => 1.0,
            Budget::Rays(_) => state.cost,
        }
    }
}

/// [`Prediction::mse`] of `states` (tests ask it directly; [`next_step`] makes its
/// [`Prediction`] once).
#[cfg(test)]
fn predicted_mse(states: &[PixelState], aim: &Aim, lambda: f64) -> f64 {
    Prediction::new(states, aim).mse(lambda)
}

/// The pixels as [`Prediction::mse`] reads them in each of [`solve`]'s sixty steps: each one's
/// value where it is below the maximum count (NaN, which no threshold is below, at it), cost and
/// squared error, so that a step divides nothing.
struct Prediction(Vec<(f64, f64, f64)>);

impl Prediction {
    fn new(states: &[PixelState], aim: &Aim) -> Prediction {
        Prediction(
            (states.iter())
                .map(|s| {
                    let value = if s.count < aim.max_spp {
                        s.value()
                    } else {
                        f64::NAN
                    };
                    (value, s.cost, s.squared_error)
                })
                .collect(),
        )
    }

    /// The image MSE the threshold `lambda` is predicted to reach, summed in the pixels' order:
    /// a pixel taken to its optimal count n' (where its value, falling as n^−α, reaches λ) keeps
    /// s (n/n')^α of its squared error s, and since (n/n')^α = λ/v there that is λ c, its value
    /// brought to the threshold times its cost (no power to evaluate).
    fn mse(&self, lambda: f64) -> f64 {
        (self.0.iter())
            .map(|&(value, cost, squared_error)| match value > lambda {
                true => lambda * cost,
                false => squared_error,
            })
            .sum::<f64>()
            / self.0.len().max(1) as f64
    }
}

/// The smallest λ in (0, `highest`] for which `enough(λ)` holds, by bisection on log λ (`enough`
/// holds at `highest`, where nothing is refined, and turns false as λ falls); 0 when it holds
/// everywhere.
fn solve(highest: f64, enough: impl Fn(f64) -> bool) -> f64 {
    let (mut low, mut high) = (highest * 1e-12, highest);
    if enough(low) {
        return 0.0;
    }
    for _ in 0..60 {
        let mid = (low * high).sqrt();
        // Once the midpoint is an end, every later step finds the same midpoint and leaves the
        // ends as they are (`low` is never enough): the answer is found.
        if mid == low || mid == high {
            break;
        }
        if enough(mid) {
            high = mid;
        } else {
            low = mid;
        }
    }
    high
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The count a threshold `lambda` on the value takes a pixel to: where its value, falling as
    /// n^−α, reaches `lambda`, without bound (its own count for a pixel at the maximum).
    fn optimal_count(state: &PixelState, aim: &Aim, lambda: f64) -> f64 {
        let n = state.count as f64;
        let value = state.value();
        if state.count >= aim.max_spp || value <= 0.0 {
            return n;
        }
        if lambda <= 0.0 {
            return f64::INFINITY;
        }
        (n * (value / lambda).powf(1.0 / aim.alpha)).max(n)
    }

    fn pixel(count: u32, squared_error: f64, cost: f64) -> PixelState {
        PixelState {
            count,
            squared_error,
            cost,
        }
    }

    fn aim(target_mse: Option<f64>, budget: Option<Budget>) -> Aim {
        Aim {
            target_mse,
            budget,
            max_spp: 1024,
            alpha: 1.0,
        }
    }

    /// Samples go where the squared error per ray (s / c) is highest: a noisy pixel is
    /// refined before a quiet one, and a costly one after a cheap one of equal error.
    #[test]
    fn the_highest_value_pixels_are_refined_first() {
        let states = [
            pixel(8, 1e-4, 1.0),
            pixel(8, 1e-6, 1.0),
            pixel(8, 1e-4, 16.0),
            pixel(8, 0.0, 1.0),
        ];
        // Half the MSE to reach: the noisy cheap pixel must go, the quiet one need not.
        let target = mean_squared_error(&states) * 0.5;
        let step = next_step(&states, &aim(Some(target), None)).unwrap();
        let targets: Vec<u32> = states.iter().map(|s| step.target(s, 1024)).collect();
        assert!(
            targets[0] > 8 && targets[1] == 8 && targets[3] == 8,
            "{targets:?}"
        );
        assert!(targets[2] <= targets[0], "{targets:?}");
        // A budget of 8 samples pays for doubling the best pixel only.
        let step = next_step(&states, &aim(None, Some(Budget::Samples(8.0)))).unwrap();
        let targets: Vec<u32> = states.iter().map(|s| step.target(s, 1024)).collect();
        assert_eq!(targets, [16, 8, 8, 8]);
        // Less than one doubling left, or a target met: stop.
        assert_eq!(
            next_step(&states, &aim(None, Some(Budget::Samples(7.0)))),
            None
        );
        assert_eq!(next_step(&states, &aim(Some(1.0), None)), None);
    }

    /// A round doubles a pixel whose count would be taken to √2 times or more, and with
    /// `round_up` any pixel above the threshold.
    #[test]
    fn a_step_doubles_past_the_geometric_midpoint() {
        let step = Step {
            lambda: 1.0,
            alpha: 2.0,
            round_up: false,
        };
        // α = 2: the count ratio is √(v/λ); √2 needs v/λ ≥ 2.
        assert_eq!(step.target(&pixel(8, 2.5, 1.0), 1024), 16);
        assert_eq!(step.target(&pixel(8, 1.5, 1.0), 1024), 8);
        assert_eq!(step.target(&pixel(8, 1e12, 1.0), 1024), 8 << MAX_DOUBLINGS);
        assert_eq!(step.target(&pixel(8, 1e12, 1.0), 12), 12);
        // Twice as costly, half as valuable.
        assert_eq!(step.target(&pixel(8, 2.5, 2.0), 1024), 8);
        let up = Step {
            round_up: true,
            ..step
        };
        assert_eq!(up.target(&pixel(8, 1.5, 1.0), 1024), 16);
    }

    /// The predicted MSE at the chosen λ is the target, and a threshold leaves every refined
    /// pixel at one error: a pixel with 4× the squared error gets 4× the samples (α = 1).
    #[test]
    fn a_threshold_brings_every_refined_pixel_to_one_error() {
        let states = [pixel(8, 4e-4, 1.0), pixel(8, 1e-4, 1.0)];
        let a = aim(Some(1e-5), None);
        let highest = states[0].value();
        let lambda = solve(highest, |l| predicted_mse(&states, &a, l) > 1e-5);
        let n0 = optimal_count(&states[0], &a, lambda);
        let n1 = optimal_count(&states[1], &a, lambda);
        assert!((n0 / n1 - 4.0).abs() < 1e-6, "{n0} {n1}");
        assert!((predicted_mse(&states, &a, lambda) / 1e-5 - 1.0).abs() < 1e-6);
    }

    /// Pixels at the maximum count or without error never draw samples.
    #[test]
    fn finished_pixels_stop_the_render() {
        let states = [pixel(1024, 1e-3, 1.0), pixel(8, 0.0, 1.0)];
        assert_eq!(next_step(&states, &aim(Some(1e-9), None)), None);
    }
}
