//! The command line's adaptive sampling options (`--target-error`, `--pixel-error`,
//! `--time-limit`, `--spp-budget`, `--min-spp`, `--max-spp`), its anti-aliasing by contrast
//! (`--aa-threshold`, `--aa-spp`), and how they combine with `--spp` and a scene's `[render]`
//! table.

use crate::StatusError;
use clap::Args;
use quadray::adaptive::ErrorRule;
use quadray::render::MAX_SPP;
use quadray::{Adaptive, Antialias};

/// Adaptive sampling on the command line; each option overrides the scene's value.
#[derive(Args, Debug, Default)]
pub struct SamplingArgs {
    /// Sample adaptively until the image's estimated error is at most E: the RMSE of its
    /// sRGB-encoded values in [0, 1] against the converged image (docs/sampling.md), with samples
    /// where they lower it most. Replaces the scene's fixed spp.
    #[arg(long, value_name = "E", value_parser = parse_positive, conflicts_with_all = ["spp", "pixel_error"])]
    pub target_error: Option<f64>,
    /// Sample adaptively until every pixel's estimated relative error is at most E: the standard
    /// error of its mean sRGB-encoded value over that value, below 0.1 over 0.1 (a bound on
    /// every pixel, at more samples than --target-error for the same image error).
    #[arg(long, value_name = "E", value_parser = parse_positive, conflicts_with = "spp")]
    pub pixel_error: Option<f64>,
    /// Stop adaptive sampling after about this many seconds, its error estimate included, and
    /// keep the image reached (alone: spend them where they lower the image's error most; the
    /// first round of --min-spp samples a pixel always completes).
    #[arg(long, value_name = "SECONDS", value_parser = parse_positive, conflicts_with = "spp")]
    pub time_limit: Option<f64>,
    /// Spend this many samples per pixel on average, where they lower the image's error most:
    /// the same image on any machine (with --target-error: whichever comes first).
    #[arg(long, value_name = "N", value_parser = parse_positive, conflicts_with_all = ["spp", "pixel_error"])]
    pub spp_budget: Option<f64>,
    /// Samples every pixel takes in the first adaptive round: a power of two, at least 2
    /// (default 8; 2 or 4 make a quick preview, cheaper where the image is flat but able to miss
    /// small features).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=MAX_SPP as i64), conflicts_with = "spp")]
    pub min_spp: Option<u32>,
    /// The most samples an adaptive render puts in a pixel (default 1024).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=MAX_SPP as i64), conflicts_with = "spp")]
    pub max_spp: Option<u32>,
    /// Anti-alias by contrast, as POV-Ray's +A: after the render's spp in every pixel, render
    /// again with --aa-spp samples each pixel whose 8-bit display value (over 255: 0 to 1)
    /// differs from one of its eight neighbours' by more than T in some channel. Sets no error
    /// and reports none; --spp 1 makes POV-Ray's first pass
    #[arg(long, value_name = "T", value_parser = parse_threshold, conflicts_with_all = ["target_error", "pixel_error", "time_limit", "spp_budget", "min_spp", "max_spp"])]
    pub aa_threshold: Option<f32>,
    /// Samples of a pixel anti-aliased by contrast (default 16, or four times the render's spp
    /// from 16 on)
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=MAX_SPP as i64))]
    pub aa_spp: Option<u32>,
}

/// A number in [0, 1]: a difference of display values.
fn parse_threshold(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|_| format!("expected a number, got \"{s}\""))?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "must be a number from 0 to 1 (a difference of display values), got {s}"
        ))
    }
}

/// A finite number above zero.
fn parse_positive(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("expected a number, got \"{s}\""))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a finite number above 0, got {s}"))
    }
}

impl SamplingArgs {
    /// The adaptive sampling to render with, given the scene's (`None`: a fixed spp). `--spp`
    /// (`fixed_spp`) turns adaptive sampling off; `--target-error`, `--pixel-error`,
    /// `--time-limit` or `--spp-budget` turns it on; `--min-spp` and `--max-spp` tune whichever
    /// is on, and are refused when none is.
    pub fn resolve(
        &self,
        fixed_spp: Option<u32>,
        scene: Option<Adaptive>,
    ) -> Result<Option<Adaptive>, StatusError> {
        if fixed_spp.is_some() {
            return Ok(None);
        }
        let asked = self.target_error.is_some()
            || self.pixel_error.is_some()
            || self.time_limit.is_some()
            || self.spp_budget.is_some();
        let Some(mut a) = scene.or(asked.then_some(Adaptive {
            target_error: 0.0,
            ..Adaptive::default()
        })) else {
            if self.min_spp.is_some() || self.max_spp.is_some() {
                return Err(StatusError::usage(
                    "--min-spp and --max-spp tune adaptive sampling: add --target-error E, \
                     --time-limit SECONDS or --spp-budget N (or give the scene a \
                     render.target_error)",
                ));
            }
            return Ok(None);
        };
        if let Some(e) = self.target_error {
            a.rule = ErrorRule::Image;
            a.target_error = e;
        }
        if let Some(e) = self.pixel_error {
            a.rule = ErrorRule::Pixel;
            a.target_error = e;
            a.spp_budget = None;
        }
        if let Some(n) = self.spp_budget {
            a.spp_budget = Some(n);
        }
        if let Some(t) = self.time_limit {
            a.time_limit = Some(
                quadray::adaptive::time_limit_from_secs(t)
                    .map_err(|e| StatusError::usage(format!("--time-limit: {e}")))?,
            );
        }
        if let Some(n) = self.max_spp {
            a = a.with_max_spp(n);
        }
        if let Some(n) = self.min_spp {
            a.min_spp = n;
        }
        a.validate()
            .map_err(|e| StatusError::usage(format!("adaptive sampling: {e}")))?;
        Ok(Some(a))
    }

    /// The anti-aliasing by contrast to render `spp` samples a pixel with, given the scene's and
    /// the adaptive sampling [`SamplingArgs::resolve`] chose: `--aa-threshold` turns it on (and
    /// the scene's adaptive sampling off), the command line's adaptive sampling turns the scene's
    /// off, and `--aa-spp` tunes whichever is on.
    pub fn resolve_antialias(
        &self,
        spp: u32,
        adaptive: &mut Option<Adaptive>,
        scene: Option<Antialias>,
    ) -> Result<Option<Antialias>, StatusError> {
        let mut antialias = match (self.aa_threshold, scene) {
            (Some(threshold), scene) => {
                *adaptive = None;
                Antialias {
                    threshold,
                    spp: scene.and_then(|a| a.spp),
                }
            }
            (None, Some(scene)) if adaptive.is_none() => scene,
            (None, scene) => {
                if self.aa_spp.is_some() {
                    return Err(StatusError::usage(match scene {
                        Some(_) => {
                            "--aa-spp tunes the scene's anti-aliasing by contrast, which adaptive \
                             sampling replaces here: drop --aa-spp or the adaptive option"
                        }
                        None => {
                            "--aa-spp tunes anti-aliasing by contrast: add --aa-threshold T (or \
                             give the scene a render.antialias_threshold)"
                        }
                    }));
                }
                return Ok(None);
            }
        };
        if let Some(n) = self.aa_spp {
            antialias.spp = Some(n);
        }
        antialias
            .validate(spp)
            .map_err(|e| StatusError::usage(format!("anti-aliasing: {e}")))?;
        Ok(Some(antialias))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_combine_with_the_scene() {
        let none = SamplingArgs::default();
        assert_eq!(none.resolve(None, None).unwrap(), None);
        let scene = Adaptive {
            target_error: 0.03,
            ..Adaptive::default()
        };
        assert_eq!(none.resolve(None, Some(scene)).unwrap(), Some(scene));
        assert_eq!(none.resolve(Some(4), Some(scene)).unwrap(), None);
        let target = SamplingArgs {
            target_error: Some(0.01),
            max_spp: Some(64),
            ..SamplingArgs::default()
        };
        let a = target.resolve(None, None).unwrap().unwrap();
        assert_eq!(
            (a.target_error, a.min_spp, a.max_spp),
            (0.01, quadray::adaptive::DEFAULT_MIN_SPP, 64)
        );
        let a = target.resolve(None, Some(scene)).unwrap().unwrap();
        assert_eq!(a.target_error, 0.01);
        let timed = SamplingArgs {
            time_limit: Some(1.5),
            ..SamplingArgs::default()
        };
        let a = timed.resolve(None, None).unwrap().unwrap();
        assert_eq!(a.target_error, 0.0);
        assert_eq!(a.time_limit, Some(std::time::Duration::from_millis(1500)));
        // A maximum below the scene's first round lowers the first round.
        let small = SamplingArgs {
            max_spp: Some(16),
            ..SamplingArgs::default()
        };
        let scene_32 = Adaptive {
            min_spp: 32,
            ..scene
        };
        let a = small.resolve(None, Some(scene_32)).unwrap().unwrap();
        assert_eq!((a.min_spp, a.max_spp), (16, 16));
        // A maximum that is not a power of two lowers the first round to the largest one within
        // it, which a first round must be: `--max-spp 3` renders, first round 2.
        for (max, first) in [(3, 2), (7, 4), (12, 8), (48, 8)] {
            let odd = SamplingArgs {
                target_error: Some(0.01),
                max_spp: Some(max),
                ..SamplingArgs::default()
            };
            let a = odd.resolve(None, None).unwrap().unwrap();
            assert_eq!((a.min_spp, a.max_spp), (first, max));
        }
    }

    #[test]
    fn tuning_without_adaptive_sampling_or_crossed_counts_are_usage_errors() {
        let tune = SamplingArgs {
            max_spp: Some(64),
            ..SamplingArgs::default()
        };
        let e = tune.resolve(None, None).unwrap_err();
        assert_eq!(e.status, 2);
        assert!(e.message.contains("--target-error"), "{}", e.message);
        let crossed = SamplingArgs {
            target_error: Some(0.1),
            min_spp: Some(64),
            max_spp: Some(32),
            ..SamplingArgs::default()
        };
        let e = crossed.resolve(None, None).unwrap_err();
        assert!(e.message.contains("minimum samples"), "{}", e.message);
        for bad in ["-1", "0", "nan", "inf", "x"] {
            assert!(parse_positive(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_positive("0.005"), Ok(0.005));
    }
}
