//! The textbook presentation of each quadric, shared by the explorer (`quadray quadric`) and the
//! gallery: parameters that show the shape's character inside the seed's clip cube, a view like
//! the familiar encyclopaedia figures, and the studio it is lit in.

use anyhow::{Result, anyhow};
use glam::{DVec3, Vec3};
use quadray::{
    Camera, ClipBox, Coefficients, Geometry, Light, Material, Quadric, QuadricKind, QuadricSurface,
    SceneDescription, SpecularModel, Texture, Transform,
};

/// The explorer's checkerboard colours: a warm white and a deep red.
pub const CHECKER_EVEN: glam::Vec3 = glam::Vec3::new(0.85, 0.83, 0.78);
/// The odd squares of the explorer's checkerboard.
pub const CHECKER_ODD: glam::Vec3 = glam::Vec3::new(0.55, 0.07, 0.06);

/// The explorer's textures (the seed's three, or a plain colour).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum TextureChoice {
    /// Blue → green → yellow over the clipped height range.
    Ramp,
    /// The ramp in eight flat contour bands.
    Bands,
    /// A 3-D checkerboard of 0.25-unit cubes.
    Checker,
    /// One plain colour.
    None,
}

impl TextureChoice {
    /// The core texture this choice stands for.
    pub fn texture(self) -> quadray::Texture {
        match self {
            TextureChoice::Ramp => quadray::Texture::HeightRamp,
            TextureChoice::Bands => quadray::Texture::Bands { steps: 8 },
            TextureChoice::Checker => quadray::Texture::Checker {
                size: 0.25,
                even: CHECKER_EVEN,
                odd: CHECKER_ODD,
            },
            TextureChoice::None => quadray::Texture::Constant(glam::Vec3::new(0.75, 0.72, 0.66)),
        }
    }
}

/// A quadric as shown on its own: its surface, the seed's clip cube, and an orbit view.
#[derive(Clone, Debug, PartialEq)]
pub struct Showcase {
    /// The surface (a named kind with a, b, c, or general coefficients).
    pub surface: QuadricSurface,
    /// Half-size R of the clip cube [-R, R]³ (paraboloid-like kinds: [-R, R]² × [0, 2R], moved
    /// down by R so the shape sits in the middle of the view).
    pub clip: f64,
    /// Orbit azimuth about +z from +x, degrees.
    pub yaw: f64,
    /// Orbit elevation, degrees.
    pub pitch: f64,
    /// Orbit distance from the clip box's centre (5 for the textbook views of the unit cube).
    pub distance: f64,
}

/// Vertical field of view of every showcase view, degrees.
pub const VFOV: f64 = 34.0;

/// The general quadric of the gallery and the POV-Ray peer: the one-sheet hyperboloid
/// a = b = 0.45, c = 0.55 turned 35° about x and 20° about z and moved by (0.1, −0.1, 0.05), so all
/// ten coefficients are in use.
pub const GENERAL: Coefficients = Coefficients([
    4.621003113514,
    2.543328463913,
    -0.593573491517,
    1.743376032187,
    -2.649588759447,
    7.27968528742,
    -0.617383581512,
    -0.029656174807,
    1.052284753838,
    -0.996920748511,
]);

/// The general form's equation, as text.
pub const GENERAL_EQUATION: &str = "Ax²+By²+Cz²+Dxy+Exz+Fyz+Gx+Hy+Iz+J = 0";

impl Showcase {
    /// The textbook parameters and view of `kind`.
    pub fn of(kind: QuadricKind) -> Showcase {
        use QuadricKind::*;
        // (a, b, c, yaw, pitch): chosen so the shape fills the cube without touching its faces
        // where that would cut its characteristic outline, seen from the front right and above
        // like the encyclopaedia figures.
        let (a, b, c, yaw, pitch) = match kind {
            Ellipsoid => (0.97, 0.7, 0.85, -55.0, 22.0),
            Hyperboloid1 => (0.5, 0.5, 0.6, -60.0, 18.0),
            Hyperboloid2 => (0.42, 0.42, 0.4, -60.0, 14.0),
            Cone => (0.75, 0.75, 1.0, -60.0, 16.0),
            EllipticCylinder => (0.85, 0.5, 1.0, -60.0, 22.0),
            HyperbolicCylinder => (0.35, 0.45, 1.0, -55.0, 40.0),
            ParabolicCylinder => (0.7, 1.0, 0.95, -40.0, 24.0),
            EllipticParaboloid => (0.75, 0.75, 1.3, -60.0, 24.0),
            HyperbolicParaboloid => (0.75, 0.75, 0.6, -58.0, 30.0),
        };
        Showcase {
            surface: QuadricSurface::Canonical { kind, a, b, c },
            clip: 1.0,
            yaw,
            pitch,
            distance: 5.0,
        }
    }

    /// The general quadric with coefficients `k`, seen like the named kinds.
    pub fn general(k: Coefficients) -> Showcase {
        Showcase {
            surface: QuadricSurface::General(k),
            clip: 1.0,
            yaw: -50.0,
            pitch: 20.0,
            distance: 5.0,
        }
    }

    /// Every kind in the seed's order, then the general form.
    pub fn all() -> Vec<Showcase> {
        QuadricKind::ALL
            .into_iter()
            .map(Showcase::of)
            .chain([Showcase::general(GENERAL)])
            .collect()
    }

    /// The kind's name, or `general`.
    pub fn name(&self) -> &'static str {
        match self.surface {
            QuadricSurface::Canonical { kind, .. } => kind.name(),
            QuadricSurface::General(_) => "general",
        }
    }

    /// The canonical equation, or the general form's.
    pub fn equation(&self) -> &'static str {
        match self.surface {
            QuadricSurface::Canonical { kind, .. } => kind.equation(),
            QuadricSurface::General(_) => GENERAL_EQUATION,
        }
    }

    /// Whether the surface lies on one side of z = 0 (x²/a² = z/c and x²/a² + y²/b² = z/c), so
    /// its clip box is lifted to [0, 2R] in z and the shape moved down to stay centred.
    fn one_sided(&self) -> bool {
        matches!(
            self.surface,
            QuadricSurface::Canonical {
                kind: QuadricKind::ParabolicCylinder | QuadricKind::EllipticParaboloid,
                ..
            }
        )
    }

    /// The quadric, clipped and placed, with material 0.
    pub fn quadric(&self) -> Result<Quadric> {
        let r = self.clip;
        anyhow::ensure!(
            r > 0.0 && r.is_finite(),
            "clip size must be a positive number, got {r:?}"
        );
        let (clip, shift) = if self.one_sided() {
            (
                ClipBox {
                    min: DVec3::new(-r, -r, 0.0),
                    max: DVec3::new(r, r, 2.0 * r),
                },
                DVec3::new(0.0, 0.0, -r),
            )
        } else {
            (ClipBox::cube(r), DVec3::ZERO)
        };
        let transform = Transform::from_srt(DVec3::ONE, DVec3::ZERO, shift)
            .ok_or_else(|| anyhow!("invalid placement"))?;
        let quadric = Quadric::new(self.surface, clip, transform, 0)
            .map_err(|e| anyhow!("{} quadric: {e}", self.name()))?;
        anyhow::ensure!(
            quadric.is_visible(),
            "the {} quadric does not reach into its clip box [-{r}, {r}]³: nothing would show",
            self.name()
        );
        Ok(quadric)
    }

    /// The orbit camera looking at the centre of the clip box.
    pub fn camera(&self) -> Camera {
        Camera::orbit(DVec3::ZERO, self.yaw, self.pitch, self.distance, VFOV)
    }

    /// A complete scene: the quadric with `texture`, lit by the studio lights (or, without
    /// lighting, showing its flat texture colours as the seed's "lighting off" did).
    pub fn scene(&self, texture: Texture, lighting: bool) -> Result<SceneDescription> {
        let material = if lighting {
            Material {
                texture,
                ambient: 0.18,
                diffuse: 0.82,
                specular: 0.35,
                shininess: 48.0,
                specular_model: SpecularModel::Blinn,
                reflectivity: 0.0,
                reflection_tint: 0.0,
                specular_tint: 0.0,
                emission: None,
                roughness: 0.0,
                transmission: None,
            }
        } else {
            Material {
                texture,
                ambient: 1.0,
                diffuse: 0.0,
                ..Material::default()
            }
        };
        Ok(SceneDescription {
            camera: self.camera(),
            background: BACKGROUND,
            environment: None,
            materials: vec![material],
            lights: if lighting {
                studio_lights(self.yaw)
            } else {
                Vec::new()
            },
            geometry: Geometry {
                quadrics: vec![self.quadric()?],
                ..Geometry::default()
            },
        })
    }
}

/// The background of every showcase: a deep blue-grey that the ramp's blue still stands out on.
pub const BACKGROUND: Vec3 = Vec3::new(0.012, 0.016, 0.026);

/// Three directional lights placed relative to the view azimuth `yaw`: a warm key from the upper
/// left, a cool fill from the right, and a rim light from behind that outlines the silhouette.
pub fn studio_lights(yaw: f64) -> Vec<Light> {
    let from = |azimuth: f64, elevation: f64| {
        let (sa, ca) = (yaw + azimuth).to_radians().sin_cos();
        let (se, ce) = elevation.to_radians().sin_cos();
        // Light travels from that direction towards the origin.
        -DVec3::new(ce * ca, ce * sa, se)
    };
    vec![
        Light::Directional {
            direction: from(-50.0, 50.0),
            irradiance: Vec3::new(1.0, 0.95, 0.88) * 0.95,
        },
        Light::Directional {
            direction: from(70.0, 15.0),
            irradiance: Vec3::new(0.55, 0.65, 0.85) * 0.35,
        },
        Light::Directional {
            direction: from(180.0, 35.0),
            irradiance: Vec3::new(0.9, 0.9, 1.0) * 0.45,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_showcase_builds_a_visible_valid_scene() {
        for s in Showcase::all() {
            let d = s.scene(Texture::HeightRamp, true).unwrap();
            quadray::Scene::new(d).unwrap();
            assert!(!s.equation().is_empty());
        }
        assert_eq!(Showcase::all().len(), 10);
    }

    #[test]
    fn bad_parameters_are_errors_not_panics() {
        let mut s = Showcase::of(QuadricKind::Ellipsoid);
        s.clip = -1.0;
        assert!(s.quadric().is_err());
        s.clip = 1.0;
        s.surface = QuadricSurface::Canonical {
            kind: QuadricKind::Ellipsoid,
            a: f64::NAN,
            b: 1.0,
            c: 1.0,
        };
        assert!(s.quadric().unwrap_err().to_string().contains("ellipsoid"));
        // A sphere of radius 10 around the clip cube never enters it: nothing would show.
        let g = Showcase::general(Coefficients([
            1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -100.0,
        ]));
        assert!(
            g.quadric()
                .unwrap_err()
                .to_string()
                .contains("does not reach")
        );
    }
}
