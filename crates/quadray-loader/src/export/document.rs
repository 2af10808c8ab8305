//! The glTF document [`crate::export`] builds: the binary buffer and the JSON arrays pointing into
//! it, with the writers of accessors, meshes, materials and textures.

use crate::export::ExportError;
use crate::gltf::material::EMISSIVE_STRENGTH;
use crate::gltf::quadrics_ext::{self, MaterialExtension, ShapeDef};
use crate::tessellate::TriMesh;
use glam::{DAffine3, DMat3, DVec3, Vec2, Vec3, Vec4};
use quadray::math::orthonormal_basis;
use quadray::{ImageTexture, Material, Mesh, Texture};
use serde_json::{Value, json};
use std::collections::HashMap;

/// glTF sampler and accessor enumerations used here.
pub(crate) mod gl {
    pub const FLOAT: u32 = 5126;
    pub const UNSIGNED_INT: u32 = 5125;
    pub const ARRAY_BUFFER: u32 = 34962;
    pub const ELEMENT_ARRAY_BUFFER: u32 = 34963;
    pub const REPEAT: u32 = 10497;
    pub const MIRRORED_REPEAT: u32 = 33648;
    pub const CLAMP_TO_EDGE: u32 = 33071;
    pub const NEAREST: u32 = 9728;
    pub const LINEAR: u32 = 9729;
}

/// The glTF document being built: the binary buffer and the JSON arrays pointing into it.
#[derive(Default)]
pub(crate) struct Document {
    pub(crate) bin: Vec<u8>,
    pub(crate) buffer_views: Vec<Value>,
    pub(crate) accessors: Vec<Value>,
    pub(crate) meshes: Vec<Value>,
    pub(crate) materials: Vec<Value>,
    pub(crate) images: Vec<Value>,
    pub(crate) samplers: Vec<Value>,
    pub(crate) textures: Vec<Value>,
    pub(crate) nodes: Vec<Value>,
    pub(crate) cameras: Vec<Value>,
    pub(crate) lights: Vec<Value>,
    pub(crate) shapes: Vec<ShapeDef>,
    /// glTF image index by the address of the shared quadray image.
    pub(crate) image_ids: HashMap<usize, usize>,
    /// glTF material index of each variant of a quadray material that a mesh's cut-out or single
    /// side needs.
    pub(crate) masked: HashMap<MaterialVariant, usize>,
    /// Whether a material uses KHR_materials_emissive_strength (then listed as used).
    pub(crate) emissive_strength: bool,
    /// Whether a material is glass (KHR_materials_transmission and _ior then listed as used).
    pub(crate) transmission: bool,
    /// Whether a glass material is a solid (KHR_materials_volume then listed as used).
    pub(crate) volume: bool,
}

/// One mesh's vertex data, borrowed.
pub(crate) struct MeshData<'a> {
    pub(crate) positions: &'a [Vec3],
    pub(crate) normals: Option<&'a [Vec3]>,
    pub(crate) texcoords: [Option<&'a [Vec2]>; 2],
    pub(crate) colors: Option<&'a [Vec4]>,
    pub(crate) indices: &'a [[u32; 3]],
}

impl Document {
    /// Appends bytes as a new 4-byte-aligned buffer view; returns its index.
    pub(crate) fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.buffer_views.push(v);
        self.buffer_views.len() - 1
    }

    /// A float accessor of `count` elements of `kind`; POSITION accessors need `min`/`max`.
    pub(crate) fn floats(&mut self, data: &[f32], count: usize, kind: &str, bounds: bool) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(gl::ARRAY_BUFFER));
        let mut a =
            json!({"bufferView": view, "componentType": gl::FLOAT, "count": count, "type": kind});
        if bounds {
            let width = data.len() / count.max(1);
            let mut lo = vec![f32::INFINITY; width];
            let mut hi = vec![f32::NEG_INFINITY; width];
            for chunk in data.chunks_exact(width) {
                for (k, &x) in chunk.iter().enumerate() {
                    lo[k] = lo[k].min(x);
                    hi[k] = hi[k].max(x);
                }
            }
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    pub(crate) fn indices(&mut self, tris: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = tris
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let view = self.view(&bytes, Some(gl::ELEMENT_ARRAY_BUFFER));
        self.accessors.push(json!({
            "bufferView": view, "componentType": gl::UNSIGNED_INT, "count": tris.len() * 3, "type": "SCALAR"
        }));
        self.accessors.len() - 1
    }

    /// Adds a one-primitive mesh; returns its index.
    pub(crate) fn mesh(&mut self, name: &str, m: &MeshData<'_>, material: usize) -> usize {
        let flat = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
        let mut attributes = serde_json::Map::new();
        let pos = self.floats(&flat(m.positions), m.positions.len(), "VEC3", true);
        attributes.insert("POSITION".into(), json!(pos));
        if let Some(n) = m.normals {
            // glTF requires unit normals; a zero normal (a loader's degenerate input) becomes +z.
            let unit: Vec<Vec3> = n
                .iter()
                .map(|v| v.try_normalize().unwrap_or(Vec3::Z))
                .collect();
            let a = self.floats(&flat(&unit), n.len(), "VEC3", false);
            attributes.insert("NORMAL".into(), json!(a));
        }
        for (set, uv) in m.texcoords.iter().enumerate() {
            if let Some(uv) = uv {
                let data: Vec<f32> = uv.iter().flat_map(|t| t.to_array()).collect();
                let a = self.floats(&data, uv.len(), "VEC2", false);
                attributes.insert(format!("TEXCOORD_{set}"), json!(a));
            }
        }
        if let Some(c) = m.colors {
            let data: Vec<f32> = c.iter().flat_map(|v| v.to_array()).collect();
            let a = self.floats(&data, c.len(), "VEC4", false);
            attributes.insert("COLOR_0".into(), json!(a));
        }
        let idx = self.indices(m.indices);
        self.meshes.push(json!({
            "name": name,
            "primitives": [{"attributes": attributes, "indices": idx, "material": material}]
        }));
        self.meshes.len() - 1
    }

    /// Adds a fallback mesh, if the tessellation produced any triangle.
    pub(crate) fn fallback(&mut self, name: &str, t: &TriMesh, material: usize) -> Option<usize> {
        (!t.indices.is_empty()).then(|| {
            let data = MeshData {
                positions: &t.positions,
                normals: Some(&t.normals),
                texcoords: [None, None],
                colors: None,
                indices: &t.indices,
            };
            self.mesh(name, &data, material)
        })
    }

    pub(crate) fn node(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// A glTF texture for an image texture (image written once per shared image).
    pub(crate) fn texture(&mut self, t: &ImageTexture) -> Result<usize, ExportError> {
        let key = std::sync::Arc::as_ptr(&t.map.image) as usize;
        let image = match self.image_ids.get(&key) {
            Some(&i) => i,
            None => {
                let img = &t.map.image;
                let rgba: Vec<u8> = img.texels().iter().flatten().copied().collect();
                let mut png = Vec::new();
                image::RgbaImage::from_raw(img.width(), img.height(), rgba)
                    .ok_or_else(|| ExportError::Unsupported("texture size mismatch".into()))?
                    .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
                    .map_err(|e| {
                        ExportError::Unsupported(format!("cannot encode a texture as PNG: {e}"))
                    })?;
                let view = self.view(&png, None);
                self.images
                    .push(json!({"bufferView": view, "mimeType": "image/png"}));
                self.image_ids.insert(key, self.images.len() - 1);
                self.images.len() - 1
            }
        };
        let wrap = |w: quadray::Wrap| match w {
            quadray::Wrap::Repeat => gl::REPEAT,
            quadray::Wrap::MirroredRepeat => gl::MIRRORED_REPEAT,
            quadray::Wrap::ClampToEdge => gl::CLAMP_TO_EDGE,
        };
        let mag = match t.map.filter {
            quadray::Filter::Nearest => gl::NEAREST,
            quadray::Filter::Bilinear => gl::LINEAR,
        };
        self.samplers.push(json!({
            "wrapS": wrap(t.map.wrap[0]), "wrapT": wrap(t.map.wrap[1]), "magFilter": mag
        }));
        self.textures
            .push(json!({"source": image, "sampler": self.samplers.len() - 1}));
        Ok(self.textures.len() - 1)
    }

    /// The glTF material for quadray material `m`: a PBR approximation plus the exact parameters.
    pub(crate) fn material(&mut self, name: &str, m: &Material) -> Result<Value, ExportError> {
        let (base, image) = match &m.texture {
            Texture::Constant(c) => (*c, None),
            // Other viewers get a representative colour of the procedural textures.
            Texture::HeightRamp | Texture::Bands { .. } => {
                (quadray::texture::height_ramp(0.5), None)
            }
            Texture::Checker { even, odd, .. } => ((*even + *odd) * 0.5, None),
            Texture::Image(t) => (t.factor, Some(t)),
        };
        // Inverse of the import's mapping where it is one-to-one: a mirror is a polished metal.
        let roughness = if m.reflectivity > 0.0 {
            1.0 - m.reflectivity.sqrt()
        } else if m.specular > 0.0 {
            (2.0 / (m.shininess + 2.0)).powf(0.25)
        } else {
            1.0
        };
        let mut pbr = json!({
            "baseColorFactor": [base.x.min(1.0), base.y.min(1.0), base.z.min(1.0), 1.0],
            "metallicFactor": m.reflectivity,
            "roughnessFactor": roughness,
        });
        if let Some(t) = image {
            let tex = self.texture(t)?;
            pbr["baseColorTexture"] = json!({"index": tex, "texCoord": t.map.set});
        }
        let ext = MaterialExtension {
            whitted: quadrics_ext::whitted_def(m),
        };
        // quadray's surfaces are seen from both sides; glTF's default is one.
        let mut material = json!({
            "name": name,
            "pbrMetallicRoughness": pbr,
            "doubleSided": true,
            "extensions": {quadrics_ext::EXTENSION: ext},
        });
        if let Some(emission) = &m.emission {
            self.write_emission(&mut material, emission)?;
        }
        if let Some(glass) = &m.transmission {
            self.write_transmission(&mut material, glass);
        }
        Ok(material)
    }

    /// Glass as KHR_materials_transmission, KHR_materials_ior and, for a solid,
    /// KHR_materials_volume (its thickness factor 1 only says "a volume": a ray tracer measures
    /// the path inside the mesh itself).
    fn write_transmission(&mut self, material: &mut Value, glass: &quadray::Transmission) {
        use crate::gltf::transmission::{IOR, TRANSMISSION, VOLUME};
        material["extensions"][TRANSMISSION] = json!({"transmissionFactor": glass.factor});
        material["extensions"][IOR] = json!({"ior": glass.ior});
        self.transmission = true;
        if !glass.thin_walled {
            let mut volume = json!({"thicknessFactor": 1.0});
            if let Some(a) = &glass.attenuation {
                volume["attenuationColor"] = json!(a.color.to_array());
                volume["attenuationDistance"] = json!(a.distance);
            }
            material["extensions"][VOLUME] = volume;
            self.volume = true;
        }
    }

    /// glTF's emissive fields for `emission`: a factor in [0, 1] scaled by
    /// KHR_materials_emissive_strength when brighter, and the texture of an image emission.
    fn write_emission(
        &mut self,
        material: &mut Value,
        emission: &Texture,
    ) -> Result<(), ExportError> {
        let (factor, image) = match emission {
            Texture::Constant(c) => (*c, None),
            Texture::Image(t) => (t.factor, Some(t)),
            // Procedural emission: a representative colour, as for base colours.
            Texture::HeightRamp | Texture::Bands { .. } => {
                (quadray::texture::height_ramp(0.5), None)
            }
            Texture::Checker { even, odd, .. } => ((*even + *odd) * 0.5, None),
        };
        let peak = factor.max_element();
        if peak > 1.0 {
            material["emissiveFactor"] = json!((factor / peak).to_array());
            material["extensions"][EMISSIVE_STRENGTH] = json!({"emissiveStrength": peak});
            self.emissive_strength = true;
        } else {
            material["emissiveFactor"] = json!(factor.to_array());
        }
        if let Some(t) = image {
            let tex = self.texture(t)?;
            material["emissiveTexture"] = json!({"index": tex, "texCoord": t.map.set});
        }
        Ok(())
    }

    /// The glTF material for `mesh` drawn with quadray material `id`: that material, or a copy
    /// with the mesh's alpha cut-out and single side.
    pub(crate) fn mesh_material(&mut self, mesh: &Mesh, id: u32) -> usize {
        let mask = mesh.alpha_mask();
        if mask.is_none() && !mesh.single_sided() {
            return id as usize;
        }
        let key = (
            id,
            mask.map(|m| (m.cutoff.to_bits(), m.factor.to_bits(), m.stochastic)),
            mesh.single_sided(),
        );
        if let Some(&m) = self.masked.get(&key) {
            return m;
        }
        let mut copy = self.materials[id as usize].clone();
        copy["doubleSided"] = json!(!mesh.single_sided());
        if let Some(mask) = mask {
            if mask.stochastic {
                copy["alphaMode"] = json!("BLEND");
            } else {
                copy["alphaMode"] = json!("MASK");
                copy["alphaCutoff"] = json!(mask.cutoff);
            }
            copy["pbrMetallicRoughness"]["baseColorFactor"][3] = json!(mask.factor);
        }
        self.materials.push(copy);
        self.masked.insert(key, self.materials.len() - 1);
        self.materials.len() - 1
    }
}

/// A quadray material as a mesh draws it: (material, the coverage's cutoff and factor bits and
/// whether it is stochastic, single-sided).
pub(crate) type MaterialVariant = (u32, Option<(u32, u32, bool)>, bool);

/// Sets a node's matrix (column-major) from an affine map, leaving the identity unwritten as the
/// spec asks.
pub(crate) fn set_matrix(node: &mut Value, a: &DAffine3) {
    if *a != DAffine3::IDENTITY {
        node["matrix"] = json!(glam::DMat4::from(*a).to_cols_array());
    }
}

/// An affine map whose local −z is `direction` and local +y the part of `up` orthogonal to it.
pub(crate) fn looking(from: DVec3, direction: DVec3, up: DVec3) -> DAffine3 {
    let back = -direction.normalize();
    let right = up
        .cross(back)
        .try_normalize()
        .unwrap_or_else(|| orthonormal_basis(back).0);
    let true_up = back.cross(right);
    DAffine3::from_mat3_translation(DMat3::from_cols(right, true_up, back), from)
}
