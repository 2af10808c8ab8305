//! `[[light]]`: point, directional and spot lights.

use super::*;

impl Builder<'_> {
    pub(super) fn light(&self, l: &LightSpec, key: &str) -> Result<Light, LoadError> {
        let color = l
            .color
            .as_ref()
            .map(|c| self.colour(c, &format!("{key}.color")))
            .transpose()?
            .unwrap_or(Vec3::ONE);
        let intensity = self.non_negative(&l.intensity, &format!("{key}.intensity"), 1.0)?;
        let unused = |field: &Option<Spanned<V3>>, name: &str, kind: &str| match field {
            Some(v) => Err(self.err(
                v.span(),
                format!("{key}.{name}"),
                format!("a {kind} light has no {name}"),
            )),
            None => Ok(()),
        };
        let kind = l.kind.get_ref().as_str();
        if kind != "spot" {
            for (field, name) in [
                (&l.inner_angle, "inner_angle"),
                (&l.outer_angle, "outer_angle"),
            ] {
                if let Some(v) = field {
                    return Err(self.err(
                        v.span(),
                        format!("{key}.{name}"),
                        format!("a {kind} light has no {name} (only spot lights do)"),
                    ));
                }
            }
        }
        match kind {
            "spot" => self.spot_light(l, color * intensity, key),
            "point" => {
                unused(&l.direction, "direction", "point")?;
                let p = l.position.as_ref().ok_or_else(|| {
                    self.err(
                        l.kind.span(),
                        format!("{key}.position"),
                        "a point light needs `position`",
                    )
                })?;
                let position = self.vec3(p, &format!("{key}.position"))?;
                // `falloff = false`: POV-Ray's classic light, the same irradiance at any distance.
                if l.falloff.as_ref().is_some_and(|f| !*f.get_ref()) {
                    return Ok(Light::PointNoFalloff {
                        position,
                        irradiance: color * intensity,
                    });
                }
                Ok(Light::Point {
                    position,
                    intensity: color * intensity,
                })
            }
            "directional" => {
                unused(&l.position, "position", "directional")?;
                if let Some(f) = &l.falloff {
                    return Err(self.err(
                        f.span(),
                        format!("{key}.falloff"),
                        "a directional light has no falloff",
                    ));
                }
                let d = l.direction.as_ref().ok_or_else(|| {
                    self.err(
                        l.kind.span(),
                        format!("{key}.direction"),
                        "a directional light needs `direction`",
                    )
                })?;
                Ok(Light::Directional {
                    direction: self.unit(d, &format!("{key}.direction"))?,
                    irradiance: color * intensity,
                })
            }
            other => Err(self.err(
                l.kind.span(),
                format!("{key}.type"),
                format!(
                    "unknown light type \"{other}\" (point, directional, spot){}",
                    did_you_mean(other, ["point", "directional", "spot"])
                ),
            )),
        }
    }

    /// A spot light: `position`, `direction`, and the cone's `inner_angle` and `outer_angle` in
    /// degrees (0 and 45 unless given), with `intensity` its colour times its intensity.
    fn spot_light(&self, l: &LightSpec, intensity: Vec3, key: &str) -> Result<Light, LoadError> {
        if let Some(f) = l.falloff.as_ref().filter(|f| !*f.get_ref()) {
            return Err(self.err(
                f.span(),
                format!("{key}.falloff"),
                "a spot light always falls off with the inverse square of the distance",
            ));
        }
        let need = |name: &str| {
            self.err(
                l.kind.span(),
                format!("{key}.{name}"),
                format!("a spot light needs `{name}`"),
            )
        };
        let position = l.position.as_ref().ok_or_else(|| need("position"))?;
        let position = self.vec3(position, &format!("{key}.position"))?;
        let direction = l.direction.as_ref().ok_or_else(|| need("direction"))?;
        let direction = self.unit(direction, &format!("{key}.direction"))?;
        let angle =
            |v: &Option<Spanned<f64>>, name: &str, default: f64| -> Result<f64, LoadError> {
                let Some(v) = v else { return Ok(default) };
                let a = self.number(v, &format!("{key}.{name}"))?;
                if !(0.0..=180.0).contains(&a) {
                    return Err(self.err(
                        v.span(),
                        format!("{key}.{name}"),
                        format!("must be an angle in [0, 180] degrees, got {a}"),
                    ));
                }
                Ok(a)
            };
        let inner = angle(&l.inner_angle, "inner_angle", 0.0)?;
        let outer = angle(&l.outer_angle, "outer_angle", 45.0)?;
        if inner > outer {
            let span = l.inner_angle.as_ref().map_or(l.kind.span(), |v| v.span());
            return Err(self.err(
                span,
                format!("{key}.inner_angle"),
                format!("must not exceed outer_angle ({outer}), got {inner}"),
            ));
        }
        Ok(Light::Spot {
            position,
            direction,
            intensity,
            cos_inner: inner.to_radians().cos(),
            cos_outer: outer.to_radians().cos(),
        })
    }
}
