//! glTF materials (pbrMetallicRoughness) mapped onto quadray's Whitted material.
//!
//! Whitted shading has a diffuse term, a Phong/Blinn highlight and a perfect mirror; PBR has a
//! base colour, a metalness and a microfacet roughness. The mapping (also in
//! `docs/import.md`):
//!
//! | glTF | quadray |
//! |---|---|
//! | `baseColorFactor` (linear RGB), `baseColorTexture` (sRGB) | base colour: `Texture::Image` scaled by the factor, or `Texture::Constant`; `COLOR_0` multiplies it |
//! | sampler `wrapS`/`wrapT`, `magFilter`; `texCoord`; KHR_texture_transform | the image's wrap modes, nearest or bilinear filtering, the coordinate set; the transform is applied to the mesh's coordinates at load |
//! | roughness r | `roughness` r: the GGX lobe (α = r²) of the highlights (`specular_model` GGX: glTF's specular BRDF, the glTF-Sample-Viewer's) and of metals' reflections; `shininess` n = 2/α² − 2 only tells other renderers the lobe's width |
//! | metallic m, roughness r | `reflectivity` = m, `roughness` = r: a metal reflects its surroundings, sharply when polished and blurred by the GGX lobe of its roughness when rough ([`quadray::microfacet`]); `reflection_tint` = m: metals reflect in their base colour |
//! | metallic m | `specular` 0.04, `specular_tint` m: F₀ = mix(0.04, base colour, m) ([`Material::fresnel_f0`]), Schlick's Fresnel towards grazing, for highlights and reflections |
//! | metallic m | `ambient` = 0.1·(1 − m), `diffuse` = 0.9·(1 − m): a metal has no diffuse term |
//! | `alphaMode` MASK, `alphaCutoff`, base colour alpha | an [`AlphaMask`] cut-out on the mesh (tested inside intersection) |
//! | `alphaMode` BLEND | a stochastic [`AlphaMask`]: alpha is each ray's chance to keep the hit |
//! | KHR_materials_unlit | `ambient` 1, everything else 0: the base colour as is |
//! | `extensions.QUADRAY_quadrics.whitted` | quadray's parameters exactly, overriding all of the above |
//! | `emissiveFactor`, `emissiveTexture` (sRGB), KHR_materials_emissive_strength | `emission`: their product, the surface's own light, seen directly and in mirrors (it lights nothing else) |
//! | KHR_materials_transmission, KHR_materials_ior, KHR_materials_volume | glass: [`crate::gltf::transmission`] |
//! | `normalTexture` (its `scale` and coordinate set) | a tangent-space [`NormalMap`] on the meshes drawn with it, with the file's TANGENTs or MikkTSpace's |
//! | metallicRoughnessTexture | its mean metalness and roughness, with a note |
//! | occlusionTexture | ignored, with a note |

use crate::gltf::document::GltfFile;
use crate::gltf::quadrics_ext::{self, MaterialExtension};
use crate::gltf::resources::read_image;
use glam::{Vec2, Vec3};
use quadray::{
    AlphaMask, ColorEncoding, Filter, Image, ImageMap, ImageTexture, Material, NormalMap,
    SpecularModel, Texture, Wrap,
};
use std::collections::{BTreeSet, HashMap};
use std::sync::Arc;

/// An affine map of texture coordinates (KHR_texture_transform): `uv' = offset + M·uv`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// The coordinate set it applies to.
    pub set: usize,
    /// Columns of M.
    pub matrix: [Vec2; 2],
    /// The offset.
    pub offset: Vec2,
}

impl UvTransform {
    /// KHR_texture_transform's `translation · rotation · scale`, with the rotation matrix of the
    /// extension's GLSL (`mat3(cos, sin, 0, -sin, cos, 0, 0, 0, 1)`, column-major).
    pub fn from_khr(set: usize, offset: Vec2, rotation: f32, scale: Vec2) -> UvTransform {
        let (sin, cos) = rotation.sin_cos();
        UvTransform {
            set,
            matrix: [
                Vec2::new(cos, sin) * scale.x,
                Vec2::new(-sin, cos) * scale.y,
            ],
            offset,
        }
    }

    /// Applies the map to one coordinate pair.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.offset + self.matrix[0] * uv.x + self.matrix[1] * uv.y
    }
}

/// A glTF material as quadray uses it: a material index plus what the mesh must carry.
#[derive(Clone, Debug)]
pub struct MaterialUse {
    /// Index into the imported material list.
    pub id: u32,
    /// The cut-out, for alpha mode MASK.
    pub mask: Option<AlphaMask>,
    /// A texture coordinate transform to bake into the mesh.
    pub uv_transform: Option<UvTransform>,
    /// Whether meshes drawn with it are seen from the front only (`doubleSided: false`).
    pub single_sided: bool,
    /// The tangent-space normal map meshes drawn with it carry (`normalTexture`).
    pub normal_map: Option<NormalMap>,
}

/// Converts glTF materials on first use, and their images once each.
pub struct Materials<'a> {
    file: &'a GltfFile,
    converted: HashMap<Option<usize>, MaterialUse>,
    images: HashMap<usize, Option<Arc<Image>>>,
    budget: crate::image_file::TextureBudget,
    /// The converted materials with their names, in first-use order.
    pub list: Vec<(String, Material)>,
    ignored: BTreeSet<&'static str>,
    /// Whether a metallicRoughnessTexture was averaged into its material's factors.
    averaged_metal_roughness: bool,
}

impl<'a> Materials<'a> {
    /// An empty table for `file`.
    pub fn new(file: &'a GltfFile, budget: crate::image_file::TextureBudget) -> Materials<'a> {
        Materials {
            file,
            budget,
            converted: HashMap::new(),
            images: HashMap::new(),
            list: Vec::new(),
            ignored: BTreeSet::new(),
            averaged_metal_roughness: false,
        }
    }

    /// The quadray material for glTF material `m`, converting it on first use.
    pub fn get(
        &mut self,
        m: &gltf::Material<'_>,
        notes: &mut Vec<String>,
    ) -> Result<MaterialUse, String> {
        if let Some(u) = self.converted.get(&m.index()) {
            return Ok(u.clone());
        }
        let converted = self.convert(m, notes)?;
        self.converted.insert(m.index(), converted.clone());
        Ok(converted)
    }

    /// The glTF default material (for shapes that name none): white, metallic 1, roughness 1.
    pub fn default_material(&mut self) -> MaterialUse {
        if let Some(u) = self.converted.get(&None) {
            return u.clone();
        }
        let material = pbr_to_whitted(Texture::Constant(Vec3::ONE), 1.0, 1.0);
        let used = MaterialUse {
            id: self.list.len() as u32,
            mask: None,
            uv_transform: None,
            // The default material is single-sided, as every material that does not say.
            single_sided: true,
            normal_map: None,
        };
        self.list.push(("default".into(), material));
        self.converted.insert(None, used.clone());
        used
    }

    /// Notes on the material features the file uses that quadray approximates or ignores.
    pub fn feature_notes(&self) -> Vec<String> {
        let mut notes = Vec::new();
        if self.averaged_metal_roughness {
            notes.push(
                "metallicRoughnessTexture: each texture's mean metalness and roughness stand for it (quadray's materials are uniform)"
                    .to_string(),
            );
        }
        if !self.ignored.is_empty() {
            notes.push(format!(
                "material features ignored: {}",
                self.ignored.iter().copied().collect::<Vec<_>>().join(", ")
            ));
        }
        notes
    }

    fn convert(
        &mut self,
        m: &gltf::Material<'_>,
        notes: &mut Vec<String>,
    ) -> Result<MaterialUse, String> {
        let label = match (m.index(), m.name()) {
            (Some(i), Some(n)) => format!("material {i} \"{n}\""),
            (Some(i), None) => format!("material {i}"),
            (None, _) => "the default material".to_string(),
        };
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, alpha] = pbr.base_color_factor();
        let base = Vec3::new(r, g, b);
        if !(base.is_finite() && alpha.is_finite()) {
            return Err(format!("{label}: baseColorFactor is not finite"));
        }
        let base = base.clamp(Vec3::ZERO, Vec3::ONE);
        let (metallic, roughness) = self.metal_roughness(&pbr, notes);
        let (map, uv_transform) = self.base_color_map(&pbr, &label, notes);
        let normal_map = self.normal_map(m, &label, uv_transform.as_ref(), notes);
        if m.occlusion_texture().is_some() {
            self.ignored.insert("occlusionTexture");
        }
        let transmission = crate::gltf::transmission::transmission_of(m, &label, notes)?;
        let emission = self.emission(m, &label, uv_transform.as_ref(), notes)?;
        let texture = match &map {
            Some(map) => Texture::Image(ImageTexture {
                map: map.clone(),
                factor: base,
            }),
            None => Texture::Constant(base),
        };
        let mask = coverage(m, alpha.clamp(0.0, 1.0), &map);
        let material = if let Some(ext) = m.extension_value(quadrics_ext::EXTENSION) {
            let key = format!("extensions.{}", quadrics_ext::EXTENSION);
            let ext: MaterialExtension = quadrics_ext::read_extension(ext, &key)
                .map_err(|(key, message)| format!("{label}: {key}: {message}"))?;
            quadrics_ext::whitted_material(&ext.whitted, texture)
                .map_err(|e| format!("{label}: extensions.{}: {e}", quadrics_ext::EXTENSION))?
        } else if m.unlit() {
            Material {
                texture,
                ambient: 1.0,
                diffuse: 0.0,
                specular: 0.0,
                reflectivity: 0.0,
                ..Material::default()
            }
        } else {
            pbr_to_whitted(texture, metallic, roughness)
        };
        let material = Material {
            emission,
            transmission,
            ..material
        };
        let id = self.list.len() as u32;
        let name = m
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| match m.index() {
                Some(i) => format!("material {i}"),
                None => "default".into(),
            });
        // A glass solid is left through its back faces: culling them would trap every ray that
        // entered (and its shadow rays, absorbed without end).
        let solid_glass = material.transmission.is_some_and(|t| !t.thin_walled);
        self.list.push((name, material));
        Ok(MaterialUse {
            id,
            mask,
            uv_transform,
            single_sided: !m.double_sided() && !solid_glass,
            normal_map,
        })
    }
}

impl Materials<'_> {
    /// The image and sampler of a texture reference, read once per image; `None`, with a
    /// warning that says the `fallback` is used, when the image cannot be read.
    fn image_map(
        &mut self,
        texture: &gltf::Texture<'_>,
        set: usize,
        fallback: &str,
        notes: &mut Vec<String>,
    ) -> Option<ImageMap> {
        let cached = self.image(texture, fallback, notes);
        let sampler = texture.sampler();
        let wrap = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
            gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        };
        let filter = match sampler.mag_filter() {
            Some(gltf::texture::MagFilter::Nearest) => Filter::Nearest,
            _ => Filter::Bilinear,
        };
        Some(ImageMap {
            image: cached?,
            wrap: [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())],
            filter,
            set: set as u8,
        })
    }

    /// A texture's decoded image, read once per image; `None`, with a warning that says the
    /// `fallback` is used, when it cannot be read.
    fn image(
        &mut self,
        texture: &gltf::Texture<'_>,
        fallback: &str,
        notes: &mut Vec<String>,
    ) -> Option<Arc<Image>> {
        let image = texture.source();
        if let Some(cached) = self.images.get(&image.index()) {
            return cached.clone();
        }
        let read = match read_image(self.file, &image, &self.budget) {
            Ok(img) => Some(Arc::new(img)),
            Err(e) => {
                notes.push(format!(
                    "warning: image {}: texture unavailable ({e}); using the {fallback}",
                    image.index()
                ));
                None
            }
        };
        self.images.insert(image.index(), read.clone());
        read
    }

    /// Metalness and roughness scaled by the metallicRoughnessTexture's means (its blue and green
    /// channels, linear): quadray's materials are uniform, so the texture's average stands for it.
    fn metal_roughness(
        &mut self,
        pbr: &gltf::material::PbrMetallicRoughness<'_>,
        notes: &mut Vec<String>,
    ) -> (f32, f32) {
        let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
        let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
        let Some(info) = pbr.metallic_roughness_texture() else {
            return (metallic, roughness);
        };
        let Some(image) = self.image(&info.texture(), "metallic and roughness factors", notes)
        else {
            return (metallic, roughness);
        };
        let texels = image.texels();
        let mean = |channel: usize| {
            texels.iter().map(|t| t[channel] as f64).sum::<f64>() / (255.0 * texels.len() as f64)
        };
        self.averaged_metal_roughness = true;
        (metallic * mean(2) as f32, roughness * mean(1) as f32)
    }

    /// The base colour texture's image map, if it has a readable one, and its KHR_texture_transform
    /// (baked into the mesh's coordinates of its set).
    fn base_color_map(
        &mut self,
        pbr: &gltf::material::PbrMetallicRoughness<'_>,
        label: &str,
        notes: &mut Vec<String>,
    ) -> (Option<ImageMap>, Option<UvTransform>) {
        let Some(info) = pbr.base_color_texture() else {
            return (None, None);
        };
        let (set, uv_transform) = lookup(&info);
        let set = kept_set(set, label, "base colour texture", notes);
        let map = self.image_map(&info.texture(), set, "base colour", notes);
        (map, uv_transform)
    }

    /// The tangent-space normal map of material `m`, read linearly, if it has a readable one.
    fn normal_map(
        &mut self,
        m: &gltf::Material<'_>,
        label: &str,
        base_transform: Option<&UvTransform>,
        notes: &mut Vec<String>,
    ) -> Option<NormalMap> {
        let info = m.normal_texture()?;
        let set = info.tex_coord() as usize;
        if set > 1 {
            notes.push(format!(
                "{label}: the normal map reads TEXCOORD_{set}; quadray keeps sets 0 and 1, so it is skipped"
            ));
            return None;
        }
        if base_transform.is_some_and(|b| b.set == set) {
            notes.push(format!(
                "{label}: the normal map is looked up through the base colour texture's KHR_texture_transform (a mesh carries one)"
            ));
        }
        let map = self.image_map(&info.texture(), set, "interpolated normals", notes)?;
        // Normals are data, not colours: the same texels, read without the sRGB curve.
        let image = &map.image;
        let bytes = image.texels().iter().flatten().copied().collect();
        let linear =
            Image::from_rgba8(image.width(), image.height(), bytes, ColorEncoding::Linear).ok()?;
        Some(NormalMap {
            map: ImageMap {
                image: Arc::new(linear),
                ..map
            },
            scale: info.scale(),
        })
    }

    /// The light material `m` gives off: emissiveFactor × emissiveTexture (sRGB) ×
    /// KHR_materials_emissive_strength, or `None` when it is black.
    fn emission(
        &mut self,
        m: &gltf::Material<'_>,
        label: &str,
        base_transform: Option<&UvTransform>,
        notes: &mut Vec<String>,
    ) -> Result<Option<Texture>, String> {
        let strength = m.emissive_strength().unwrap_or(1.0);
        if !(strength.is_finite() && strength >= 0.0) {
            return Err(format!(
                "{label}: {EMISSIVE_STRENGTH}.emissiveStrength must be a number >= 0, got {strength}"
            ));
        }
        let factor = Vec3::from_array(m.emissive_factor()) * strength;
        if !(factor.is_finite() && factor.min_element() >= 0.0) {
            return Err(format!(
                "{label}: emissiveFactor must be finite and non-negative"
            ));
        }
        if factor == Vec3::ZERO {
            return Ok(None);
        }
        let Some(info) = m.emissive_texture() else {
            return Ok(Some(Texture::Constant(factor)));
        };
        let (set, transform) = lookup(&info);
        // A mesh's coordinates carry one transform, the base colour texture's.
        if transform.as_ref() != base_transform && base_transform.is_none_or(|b| b.set == set) {
            notes.push(format!(
                "{label}: the emissive texture's KHR_texture_transform differs from the base colour texture's; it is looked up through the base colour's"
            ));
        }
        let set = kept_set(set, label, "emissive texture", notes);
        Ok(Some(
            match self.image_map(&info.texture(), set, "emissive factor", notes) {
                Some(map) => Texture::Image(ImageTexture { map, factor }),
                None => Texture::Constant(factor),
            },
        ))
    }
}

/// The texture coordinate set a texture reads (its KHR_texture_transform may name another) and
/// that transform.
fn lookup(info: &gltf::texture::Info<'_>) -> (usize, Option<UvTransform>) {
    let mut set = info.tex_coord() as usize;
    let transform = info.texture_transform().map(|t| {
        if let Some(s) = t.tex_coord() {
            set = s as usize;
        }
        UvTransform::from_khr(
            set,
            Vec2::from_array(t.offset()),
            t.rotation(),
            Vec2::from_array(t.scale()),
        )
    });
    (set, transform)
}

/// `set`, or set 0 with a note naming `what` when it is beyond the two sets quadray keeps.
fn kept_set(set: usize, label: &str, what: &str, notes: &mut Vec<String>) -> usize {
    if set > 1 {
        notes.push(format!(
            "{label}: {what} reads TEXCOORD_{set}; quadray keeps sets 0 and 1, so set 0 is used"
        ));
        return 0;
    }
    set
}

/// The coverage of material `m` with base colour alpha `alpha` and base colour texture `map`:
/// none (OPAQUE), a cut-out (MASK), or stochastic (BLEND: a probability per ray, converging to the
/// blend over a pixel's samples).
fn coverage(m: &gltf::Material<'_>, alpha: f32, map: &Option<ImageMap>) -> Option<AlphaMask> {
    let (cutoff, stochastic) = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => return None,
        gltf::material::AlphaMode::Mask => (m.alpha_cutoff().unwrap_or(0.5).clamp(0.0, 1.0), false),
        gltf::material::AlphaMode::Blend => (0.5, true),
    };
    Some(AlphaMask {
        cutoff,
        stochastic,
        factor: alpha,
        map: map.clone(),
    })
}

/// The glTF extension that scales emission beyond 1.
pub const EMISSIVE_STRENGTH: &str = "KHR_materials_emissive_strength";

/// The Whitted material for PBR parameters (see the module's table): glTF's specular BRDF for
/// the lights' highlights ([`SpecularModel::Ggx`]), a mirror or glossy reflection for metals.
/// The diffuse albedo and the mirror's weight stay at or below 1.
pub fn pbr_to_whitted(texture: Texture, metallic: f32, roughness: f32) -> Material {
    let alpha = roughness * roughness;
    // The Blinn–Phong exponent of the same lobe width: not used by the GGX highlight, but what
    // `quadray convert` tells other renderers (and POV-Ray's translation) about the highlight.
    let shininess = if alpha > 0.0 {
        (2.0 / (alpha * alpha) - 2.0).clamp(1.0, 1e4)
    } else {
        1e4
    };
    // F₀ = mix(0.04, base colour, metallic) ([`Material::fresnel_f0`]): 4% for a dielectric,
    // the base colour for a metal.
    Material {
        texture,
        ambient: Material::default().ambient * (1.0 - metallic),
        diffuse: Material::default().diffuse * (1.0 - metallic),
        specular: 0.04,
        shininess,
        specular_model: SpecularModel::Ggx,
        specular_tint: metallic,
        reflectivity: metallic,
        reflection_tint: metallic,
        roughness,
        ..Material::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pbr_mapping_endpoints() {
        let gold = Texture::Constant(Vec3::new(1.0, 0.8, 0.3));
        let mirror = pbr_to_whitted(gold.clone(), 1.0, 0.0);
        assert_eq!((mirror.reflectivity, mirror.reflection_tint), (1.0, 1.0));
        assert_eq!(mirror.roughness, 0.0);
        assert_eq!((mirror.shininess, mirror.specular), (1e4, 0.04));
        assert_eq!(
            mirror.fresnel_f0(Vec3::new(1.0, 0.8, 0.3)),
            Vec3::new(1.0, 0.8, 0.3)
        );
        assert_eq!(mirror.specular_model, SpecularModel::Ggx);
        // A rough metal: a fully blurred reflection, no diffuse, a broad highlight in its own
        // colour.
        let rough_metal = pbr_to_whitted(gold.clone(), 1.0, 1.0);
        assert_eq!(
            (rough_metal.reflectivity, rough_metal.roughness),
            (1.0, 1.0)
        );
        assert_eq!(rough_metal.shininess, 1.0);
        assert_eq!(rough_metal.diffuse, 0.0);
        assert_eq!(
            (rough_metal.specular, rough_metal.specular_tint),
            (0.04, 1.0)
        );
        // F₀ = mix(0.04, base, metallic): glTF's.
        let half = pbr_to_whitted(Texture::Constant(Vec3::ONE), 0.5, 0.5);
        let base = Vec3::new(1.0, 0.5, 0.0);
        assert!(
            (half.fresnel_f0(base) - (Vec3::splat(0.02) + base * 0.5))
                .abs()
                .max_element()
                < 1e-6
        );
        let plastic = pbr_to_whitted(gold, 0.0, 0.5);
        assert_eq!(plastic.reflectivity, 0.0);
        assert_eq!((plastic.diffuse, plastic.specular_tint), (0.9, 0.0));
        // r = 0.5: α = 0.25, the lobe of Blinn–Phong's n = 2/0.0625 − 2 = 30; F₀ = 0.04.
        assert!((plastic.shininess - 30.0).abs() < 1e-4);
        assert!((plastic.specular - 0.04).abs() < 1e-6);
        assert_eq!(plastic.specular_model, SpecularModel::Ggx);
    }

    /// Along the MetalRoughSpheres grid's axes the mapping moves one way: more roughness blurs
    /// the reflection and widens the highlight; more metalness strengthens the mirror, tints
    /// highlights and reflections and takes the diffuse term away; no term exceeds 1.
    #[test]
    fn pbr_mapping_is_monotone_and_bounded() {
        let steps: Vec<f32> = (0..=6).map(|i| i as f32 / 6.0).collect();
        let material = |m, r| pbr_to_whitted(Texture::Constant(Vec3::ONE), m, r);
        for &m in &steps {
            for pair in steps.windows(2) {
                let (smooth, rough) = (material(m, pair[0]), material(m, pair[1]));
                assert!(rough.reflectivity <= smooth.reflectivity);
                assert!(rough.roughness > smooth.roughness);
                assert!(rough.shininess < smooth.shininess || rough.shininess == 1.0);
                assert!(
                    rough.specular == smooth.specular,
                    "F₀ does not depend on roughness"
                );
            }
        }
        for &r in &steps {
            for pair in steps.windows(2) {
                let (dielectric, metal) = (material(pair[0], r), material(pair[1], r));
                assert!(metal.reflectivity >= dielectric.reflectivity);
                assert!(metal.diffuse < dielectric.diffuse);
                assert!(metal.specular_tint > dielectric.specular_tint);
                assert!(metal.reflection_tint > dielectric.reflection_tint);
                assert!(metal.specular >= dielectric.specular);
            }
        }
        for &m in &steps {
            for &r in &steps {
                let x = material(m, r);
                for term in [x.diffuse, x.specular, x.reflectivity] {
                    assert!((0.0..=1.0).contains(&term), "m {m}, r {r}: {x:?}");
                }
            }
        }
    }

    #[test]
    fn texture_transform_follows_the_extension_spec() {
        // The spec's T·R·S with rotation 90° (sin 1, cos 0), scale (2, 3), offset (0.5, 0.25):
        // u' = 0.5 + cos·sx·u − sin·sy·v, v' = 0.25 + sin·sx·u + cos·sy·v.
        let t = UvTransform::from_khr(
            0,
            Vec2::new(0.5, 0.25),
            std::f32::consts::FRAC_PI_2,
            Vec2::new(2.0, 3.0),
        );
        assert!((t.apply(Vec2::new(1.0, 1.0)) - Vec2::new(-2.5, 2.25)).length() < 1e-6);
    }
}
