//! `[render]`: the image's size, how it is sampled (a fixed count, anti-aliased by contrast, or
//! adaptively to a target error) and how deep its rays go.

use super::*;
use quadray::adaptive::{AdaptiveError, ErrorRule};
use quadray::{Adaptive, Antialias, AntialiasError};

impl Builder<'_> {
    /// The settings, the background and the environment (when set) of `[render]`.
    pub(super) fn render(
        &self,
        r: &RenderSpec,
    ) -> Result<(SceneSettings, Vec3, Option<Vec3>), LoadError> {
        let mut s = SceneSettings::default();
        if let Some(res) = &r.resolution {
            let [w, h] = res.get_ref().0;
            if !(1..=MAX_SIDE as i64).contains(&w) || !(1..=MAX_SIDE as i64).contains(&h) {
                return Err(self.err(
                    res.span(),
                    "render.resolution",
                    format!("each side must be between 1 and {MAX_SIDE}, got {w}x{h}"),
                ));
            }
            // The pixel count and aspect ratio, as the renderer will check them.
            check_resolution(w as u32, h as u32)
                .map_err(|e| self.err(res.span(), "render.resolution", e.to_string()))?;
            (s.width, s.height) = (w as u32, h as u32);
        }
        if let Some(v) = &r.spp {
            s.spp = self.count(v, "render.spp", MAX_SPP)?;
        }
        s.adaptive = self.adaptive(r)?;
        s.antialias = self.antialias(r, s.spp, s.adaptive.is_some())?;
        if let Some(v) = &r.max_depth {
            s.max_depth = self.count(v, "render.max_depth", MAX_DEPTH)?;
        }
        s.compact_meshes = r.compact_meshes.unwrap_or(false);
        let background = r
            .background
            .as_ref()
            .map(|v| self.colour(v, "render.background"))
            .transpose()?
            .unwrap_or(Vec3::ZERO);
        let environment = r
            .environment
            .as_ref()
            .map(|v| self.colour(v, "render.environment"))
            .transpose()?;
        Ok((s, background, environment))
    }

    /// Adaptive sampling, on when `target_error`, `pixel_error`, `time_limit` or `spp_budget` is
    /// given; `min_spp` and `max_spp` tune it and mean nothing without it, and `spp` (a fixed
    /// count) excludes it.
    fn adaptive(&self, r: &RenderSpec) -> Result<Option<Adaptive>, LoadError> {
        let asked = [
            &r.target_error,
            &r.pixel_error,
            &r.time_limit,
            &r.spp_budget,
        ];
        if asked.iter().all(|v| v.is_none()) {
            for (v, key) in [
                (&r.min_spp, "render.min_spp"),
                (&r.max_spp, "render.max_spp"),
            ] {
                if let Some(v) = v {
                    return Err(self.err(
                        v.span(),
                        key,
                        "applies to adaptive sampling only: give render.target_error, \
                         render.time_limit or render.spp_budget as well",
                    ));
                }
            }
            return Ok(None);
        }
        if let Some(spp) = &r.spp {
            return Err(self.err(
                spp.span(),
                "render.spp",
                "a fixed sample count excludes adaptive sampling (render.target_error, \
                 render.pixel_error, render.time_limit or render.spp_budget): give \
                 render.max_spp to bound the adaptive count",
            ));
        }
        let mut a = Adaptive {
            target_error: 0.0,
            ..Adaptive::default()
        };
        if let Some(v) = &r.target_error {
            a.target_error = self.positive(v, "render.target_error")?;
        }
        if let Some(v) = &r.pixel_error {
            if r.target_error.is_some() {
                return Err(self.err(
                    v.span(),
                    "render.pixel_error",
                    "give either render.target_error (the image's error) or \
                     render.pixel_error (every pixel's), not both",
                ));
            }
            a.rule = ErrorRule::Pixel;
            a.target_error = self.positive(v, "render.pixel_error")?;
        }
        if let Some(v) = &r.max_spp {
            a = a.with_max_spp(self.count(v, "render.max_spp", MAX_SPP)?);
        }
        if let Some(v) = &r.min_spp {
            // Its range (a power of two from 2 to the maximum) is checked with the maximum below;
            // a count past u32 stands as 0, which that check refuses with the range.
            a.min_spp = u32::try_from(*v.get_ref()).unwrap_or(0);
        }
        if let Some(v) = &r.time_limit {
            let secs = self.positive(v, "render.time_limit")?;
            a.time_limit = Some(
                quadray::adaptive::time_limit_from_secs(secs)
                    .map_err(|e| self.err(v.span(), "render.time_limit", e.to_string()))?,
            );
        }
        if let Some(v) = &r.spp_budget {
            a.spp_budget = Some(self.positive(v, "render.spp_budget")?);
        }
        // Only the counts and the budget can disagree here (the others were checked above).
        a.validate()
            .map_err(|e| match (&e, &r.spp_budget, &r.min_spp, &r.max_spp) {
                (AdaptiveError::SppBudget { .. }, Some(v), ..)
                | (AdaptiveError::BudgetWithPixelRule, Some(v), ..) => {
                    self.err(v.span(), "render.spp_budget", e.to_string())
                }
                (_, _, Some(v), _) => self.err(v.span(), "render.min_spp", e.to_string()),
                (_, _, None, Some(v)) => self.err(v.span(), "render.max_spp", e.to_string()),
                _ => self.err(0..0, "render", e.to_string()),
            })?;
        Ok(Some(a))
    }

    /// Anti-aliasing by contrast, on when `antialias_threshold` is given; `antialias_spp` tunes it
    /// and means nothing without it, and adaptive sampling (`adaptive`, as [`Builder::adaptive`]
    /// found it) excludes it.
    fn antialias(
        &self,
        r: &RenderSpec,
        spp: u32,
        adaptive: bool,
    ) -> Result<Option<Antialias>, LoadError> {
        let Some(threshold) = &r.antialias_threshold else {
            if let Some(v) = &r.antialias_spp {
                return Err(self.err(
                    v.span(),
                    "render.antialias_spp",
                    "applies to anti-aliasing by contrast only: give render.antialias_threshold \
                     as well",
                ));
            }
            return Ok(None);
        };
        let key = "render.antialias_threshold";
        if adaptive {
            return Err(self.err(
                threshold.span(),
                key,
                "anti-aliasing by contrast excludes adaptive sampling (render.target_error, \
                 render.pixel_error, render.time_limit, render.spp_budget): give one of them",
            ));
        }
        let antialias = Antialias {
            threshold: self.number(threshold, key)? as f32,
            spp: (r.antialias_spp.as_ref())
                .map(|v| self.count(v, "render.antialias_spp", MAX_SPP))
                .transpose()?,
        };
        antialias
            .validate(spp)
            .map_err(|e| match (&e, &r.antialias_spp) {
                (AntialiasError::Spp { .. }, Some(v)) => {
                    self.err(v.span(), "render.antialias_spp", e.to_string())
                }
                _ => self.err(threshold.span(), key, e.to_string()),
            })?;
        Ok(Some(antialias))
    }
}
