//! glTF glass: KHR_materials_transmission, KHR_materials_ior and KHR_materials_volume read into
//! a [`Transmission`].
//!
//! | glTF | quadray |
//! |---|---|
//! | `transmissionFactor` (default 0: opaque) | `Transmission::factor` |
//! | `transmissionTexture` | not sampled: the factor alone, with a note |
//! | KHR_materials_ior `ior` (default 1.5) | `Transmission::ior` |
//! | no KHR_materials_volume, or `thicknessFactor` 0 | thin-walled: light passes unbent, as glTF defines |
//! | `thicknessFactor` > 0 | a solid: refraction by Snell's law at its surface |
//! | `attenuationColor`, `attenuationDistance` (default ∞) | Beer–Lambert absorption inside the solid |
//! | `thicknessTexture` | not needed: the ray tracer measures the path inside the mesh itself |

use glam::Vec3;
use gltf::json::Value;
use quadray::{Attenuation, Transmission};

/// The extensions read here.
pub const TRANSMISSION: &str = "KHR_materials_transmission";
/// The index of refraction extension.
pub const IOR: &str = "KHR_materials_ior";
/// The volume extension.
pub const VOLUME: &str = "KHR_materials_volume";

/// The glass `m` describes, or `None` for an opaque material; `label` names the material in
/// errors and notes.
pub fn transmission_of(
    m: &gltf::Material<'_>,
    label: &str,
    notes: &mut Vec<String>,
) -> Result<Option<Transmission>, String> {
    let number = |ext: &str, key: &str| -> Option<f64> {
        m.extension_value(ext)
            .and_then(|v| v.get(key))
            .and_then(Value::as_f64)
    };
    // Present but not a number is an error, as is a negative value: never silently opaque.
    let checked = |ext: &str, key: &str| -> Result<Option<f64>, String> {
        match m.extension_value(ext).and_then(|v| v.get(key)) {
            None => Ok(None),
            Some(v) => match v.as_f64() {
                Some(x) if x >= 0.0 => Ok(Some(x)),
                _ => Err(format!(
                    "{label}: {ext}.{key} must be a number ≥ 0, got {v}"
                )),
            },
        }
    };
    let thickness = checked(VOLUME, "thicknessFactor")?.unwrap_or(0.0);
    let Some(factor) = checked(TRANSMISSION, "transmissionFactor")?.filter(|f| *f > 0.0) else {
        return Ok(None);
    };
    if factor > 1.0 {
        return Err(format!(
            "{label}: {TRANSMISSION}.transmissionFactor must be in [0, 1], got {factor}"
        ));
    }
    if m.extension_value(TRANSMISSION)
        .and_then(|v| v.get("transmissionTexture"))
        .is_some()
    {
        notes.push(format!(
            "{label}: {TRANSMISSION}.transmissionTexture is not sampled; its factor {factor} applies everywhere"
        ));
    }
    let ior = number(IOR, "ior").unwrap_or(Transmission::default().ior);
    if !(1.0..=quadray::dielectric::MAX_IOR).contains(&ior) {
        return Err(format!(
            "{label}: {IOR}.ior must be in [1, {}], got {ior}",
            quadray::dielectric::MAX_IOR
        ));
    }
    let thin_walled = m.extension_value(VOLUME).is_none() || thickness <= 0.0;
    let attenuation = if thin_walled {
        None
    } else {
        volume_attenuation(m, label)?
    };
    Ok(Some(Transmission {
        factor: factor as f32,
        ior,
        thin_walled,
        attenuation,
    }))
}

/// KHR_materials_volume's attenuation, `None` when it absorbs nothing (distance ∞ or white).
fn volume_attenuation(m: &gltf::Material<'_>, label: &str) -> Result<Option<Attenuation>, String> {
    let volume = m.extension_value(VOLUME);
    let Some(distance) = volume
        .and_then(|v| v.get("attenuationDistance"))
        .and_then(Value::as_f64)
    else {
        return Ok(None);
    };
    let color = volume
        .and_then(|v| v.get("attenuationColor"))
        .and_then(Value::as_array)
        .map(|c| c.iter().filter_map(Value::as_f64).collect::<Vec<_>>())
        .unwrap_or_else(|| vec![1.0; 3]);
    let [r, g, b] = <[f64; 3]>::try_from(color).map_err(|c| {
        format!("{label}: {VOLUME}.attenuationColor must be three numbers, got {c:?}")
    })?;
    let color = Vec3::new(r as f32, g as f32, b as f32);
    if color == Vec3::ONE {
        return Ok(None);
    }
    let a = Attenuation { color, distance };
    a.validate()
        .map_err(|e| format!("{label}: {VOLUME}: {e}"))?;
    Ok(Some(a))
}
