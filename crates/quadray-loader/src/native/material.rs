//! `[[material]]`: colours, textures and the lighting model.

use super::*;
use quadray::{Attenuation, Transmission};

impl Builder<'_> {
    pub(super) fn material(&self, m: &MaterialSpec, key: &str) -> Result<Material, LoadError> {
        let defaults = Material::default();
        let color = m
            .color
            .as_ref()
            .map(|c| self.colour(c, &format!("{key}.color")))
            .transpose()?;
        let texture = self.texture(m, color, key)?;
        let specular_model = self.specular_model(m, key)?;
        let reflectivity = self.fraction(&m.reflectivity, &format!("{key}.reflectivity"))?;
        Ok(Material {
            texture,
            ambient: self.non_negative(
                &m.ambient,
                &format!("{key}.ambient"),
                defaults.ambient as f64,
            )?,
            diffuse: self.non_negative(
                &m.diffuse,
                &format!("{key}.diffuse"),
                defaults.diffuse as f64,
            )?,
            specular: self.non_negative(
                &m.specular,
                &format!("{key}.specular"),
                defaults.specular as f64,
            )?,
            shininess: self.non_negative(
                &m.shininess,
                &format!("{key}.shininess"),
                defaults.shininess as f64,
            )?,
            specular_model,
            reflectivity,
            reflection_tint: self
                .fraction(&m.reflection_tint, &format!("{key}.reflection_tint"))?,
            specular_tint: self.fraction(&m.specular_tint, &format!("{key}.specular_tint"))?,
            emission: match &m.emission {
                Some(v) => Some(Texture::Constant(
                    self.colour(v, &format!("{key}.emission"))?,
                ))
                .filter(|t| t != &Texture::Constant(Vec3::ZERO)),
                None => None,
            },
            roughness: self.fraction(&m.roughness, &format!("{key}.roughness"))?,
            transmission: self.transmission(m, key)?,
        })
    }

    /// Glass: `transmission` with `ior`, `thin_walled` and the attenuation pair, which mean
    /// nothing without it; `transmission = 0` is an opaque material.
    fn transmission(&self, m: &MaterialSpec, key: &str) -> Result<Option<Transmission>, LoadError> {
        let factor = self.fraction(&m.transmission, &format!("{key}.transmission"))?;
        if factor == 0.0 {
            let glass_keys = [
                m.ior.as_ref().map(|v| (v.span(), "ior")),
                m.thin_walled.as_ref().map(|v| (v.span(), "thin_walled")),
                m.attenuation_color
                    .as_ref()
                    .map(|v| (v.span(), "attenuation_color")),
                m.attenuation_distance
                    .as_ref()
                    .map(|v| (v.span(), "attenuation_distance")),
            ];
            if let Some((span, name)) = glass_keys.into_iter().flatten().next() {
                return Err(self.err(
                    span,
                    format!("{key}.{name}"),
                    "only applies to a material with transmission > 0".to_string(),
                ));
            }
            return Ok(None);
        }
        let defaults = Transmission::default();
        let attenuation = match (&m.attenuation_color, &m.attenuation_distance) {
            (None, None) => None,
            (Some(c), Some(d)) => Some(Attenuation {
                color: self.colour(c, &format!("{key}.attenuation_color"))?,
                distance: self.positive(d, &format!("{key}.attenuation_distance"))?,
            }),
            (Some(v), None) => {
                return Err(self.err(
                    v.span(),
                    format!("{key}.attenuation_color"),
                    "needs attenuation_distance: the distance at which white light takes this colour"
                        .to_string(),
                ));
            }
            (None, Some(v)) => {
                return Err(self.err(
                    v.span(),
                    format!("{key}.attenuation_distance"),
                    "needs attenuation_color: the colour white light takes at this distance"
                        .to_string(),
                ));
            }
        };
        let ior = m.ior.as_ref().map_or(defaults.ior, |v| *v.get_ref());
        if !(1.0..=quadray::dielectric::MAX_IOR).contains(&ior) {
            return Err(self.err(
                m.ior.as_ref().map(|v| v.span()).unwrap_or_default(),
                format!("{key}.ior"),
                format!(
                    "must be in [1, {}] (glass is about 1.5), got {ior}",
                    quadray::dielectric::MAX_IOR
                ),
            ));
        }
        if let (Some(a), Some(c)) = (&attenuation, &m.attenuation_color)
            && let Err(problem) = a.validate()
        {
            return Err(self.err(c.span(), format!("{key}.attenuation_color"), problem));
        }
        let thin_walled = m.thin_walled.as_ref().is_some_and(|v| *v.get_ref());
        if let (true, Some(c)) = (thin_walled, &m.attenuation_color) {
            return Err(self.err(
                c.span(),
                format!("{key}.attenuation_color"),
                "a thin wall absorbs nothing: attenuation applies to solids (thin_walled = false)"
                    .to_string(),
            ));
        }
        let t = Transmission {
            factor,
            ior,
            thin_walled,
            attenuation,
        };
        Ok(Some(t))
    }

    /// The material's texture (`texture`, with `color`, `bands`, `checker_size`, `color2`),
    /// refusing a key that only applies to another texture.
    fn texture(
        &self,
        m: &MaterialSpec,
        color: Option<Vec3>,
        key: &str,
    ) -> Result<Texture, LoadError> {
        let texture_name = m.texture.as_ref().map(|t| (t.get_ref().as_str(), t.span()));
        let only_for =
            |field: Option<Range<usize>>, name: &str, texture: &str| -> Result<(), LoadError> {
                match field {
                    Some(span) => Err(self.err(
                        span,
                        format!("{key}.{name}"),
                        format!("only applies to texture = \"{texture}\""),
                    )),
                    None => Ok(()),
                }
            };
        if !matches!(texture_name, Some(("bands", _))) {
            only_for(m.bands.as_ref().map(|b| b.span()), "bands", "bands")?;
        }
        if !matches!(texture_name, Some(("checker", _))) {
            only_for(
                m.checker_size.as_ref().map(|c| c.span()),
                "checker_size",
                "checker",
            )?;
            only_for(m.color2.as_ref().map(|c| c.span()), "color2", "checker")?;
        }
        Ok(match texture_name {
            None | Some(("constant", _)) => Texture::Constant(color.unwrap_or(Vec3::splat(0.8))),
            Some(("ramp", _)) => Texture::HeightRamp,
            Some(("bands", _)) => {
                let steps = m
                    .bands
                    .as_ref()
                    .map(|b| self.count(b, &format!("{key}.bands"), 1024))
                    .transpose()?
                    .unwrap_or(8);
                Texture::Bands { steps }
            }
            Some(("checker", _)) => {
                let even = color.unwrap_or(Vec3::splat(0.4));
                let size = m
                    .checker_size
                    .as_ref()
                    .map(|s| self.positive(s, &format!("{key}.checker_size")))
                    .transpose()?
                    .unwrap_or(1.0);
                let odd = m
                    .color2
                    .as_ref()
                    .map(|c| self.colour(c, &format!("{key}.color2")))
                    .transpose()?;
                Texture::Checker {
                    size,
                    even,
                    odd: odd.unwrap_or(quadray::texture::lighten(even)),
                }
            }
            Some((other, span)) => {
                return Err(self.err(
                    span,
                    format!("{key}.texture"),
                    format!(
                        "unknown texture \"{other}\" (constant, ramp, bands, checker){}",
                        did_you_mean(other, ["constant", "ramp", "bands", "checker"])
                    ),
                ));
            }
        })
    }

    /// The material's `specular_model` (Phong unless it says Blinn).
    fn specular_model(&self, m: &MaterialSpec, key: &str) -> Result<SpecularModel, LoadError> {
        Ok(
            match m
                .specular_model
                .as_ref()
                .map(|s| (s.get_ref().as_str(), s.span()))
            {
                None | Some(("phong", _)) => SpecularModel::Phong,
                Some(("blinn", _)) => SpecularModel::Blinn,
                Some(("ggx", _)) => SpecularModel::Ggx,
                Some((other, span)) => {
                    return Err(self.err(
                        span,
                        format!("{key}.specular_model"),
                        format!(
                            "unknown model \"{other}\" (phong, blinn, ggx){}",
                            did_you_mean(other, ["phong", "blinn", "ggx"])
                        ),
                    ));
                }
            },
        )
    }

    /// A share in [0, 1] (a tint, the reflectivity, roughness or transmission), 0 when absent.
    fn fraction(&self, value: &Option<Spanned<f64>>, key: &str) -> Result<f32, LoadError> {
        let Some(v) = value else {
            return Ok(0.0);
        };
        let t = self.number(v, key)?;
        if !(0.0..=1.0).contains(&t) {
            return Err(self.err(v.span(), key, format!("must be in [0, 1], got {t}")));
        }
        Ok(t as f32)
    }
}
