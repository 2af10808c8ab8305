//! `quadray bench rays`: casts ray files through the core's ray-casting API, the same rays Embree
//! and obvhs cast in ../shared/peers/speed, and prints throughput per CPU-second and per wall
//! second with a hit count and a t checksum to compare with theirs.
//!
//! Ray files are the harness's format: the bytes `RAYS`, a little-endian u32 count, then per ray
//! six little-endian f32 (origin x y z, direction x y z). Meshes are read in the file's own
//! coordinates (no y-up rotation), as the other programs read them.

use anyhow::{Context, Result, bail};
use clap::Args;
use glam::DVec3;
use quadray::{Camera, Geometry, Material, Ray, Scene, SceneDescription};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `quadray bench rays`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct RaysArgs {
    /// The mesh: an OBJ or glTF file, read in its own coordinates.
    pub mesh: PathBuf,
    /// One or more ray files (`RAYS` format).
    #[arg(required = true)]
    pub rays: Vec<PathBuf>,
    /// Timed passes over each ray set per query (the median is reported).
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub runs: usize,
    /// Worker threads (1 for per-core throughput).
    #[arg(short = 't', long = "threads", value_name = "N", default_value_t = 1)]
    pub threads: usize,
    /// BVH builds to time (the median is reported).
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub builds: usize,
    /// Build the compact mesh BVH (`render --compact-meshes`).
    #[arg(long)]
    pub compact_meshes: bool,
}

/// Reads a `RAYS` file.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>> {
    // A regular file of at most 4 GiB (about 179 million rays): never a device or a pipe, whose
    // read would not end.
    let limit = quadray_loader::read_limited::MAX_MESH_BYTES;
    let bytes = quadray_loader::read_limited::read(path, limit)
        .with_context(|| format!("cannot read {}", path.display()))?;
    if bytes.len() < 8 || &bytes[..4] != b"RAYS" {
        bail!(
            "{}: not a ray file (expected the magic bytes RAYS)",
            path.display()
        );
    }
    let n = u32::from_le_bytes(bytes[4..8].try_into().expect("4 bytes")) as usize;
    if bytes.len() != 8 + n * 24 {
        bail!(
            "{}: the header says {n} rays ({} bytes), the file has {} bytes",
            path.display(),
            8 + n * 24,
            bytes.len()
        );
    }
    let f =
        |k: usize| f32::from_le_bytes(bytes[8 + 4 * k..12 + 4 * k].try_into().expect("4")) as f64;
    let mut rays = Vec::with_capacity(n);
    for i in 0..n {
        let k = 6 * i;
        let origin = DVec3::new(f(k), f(k + 1), f(k + 2));
        let dir = DVec3::new(f(k + 3), f(k + 4), f(k + 5));
        if !(origin.is_finite() && dir.is_finite() && dir != DVec3::ZERO) {
            bail!(
                "{}: ray {i} is not finite or has a zero direction",
                path.display()
            );
        }
        rays.push(Ray::new(origin, dir));
    }
    Ok(rays)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs the benchmark, printing `BUILD` and `RESULT` lines in the harness's format.
pub fn run(a: &RaysArgs) -> Result<()> {
    if a.runs == 0 || a.builds == 0 {
        bail!("--runs and --builds must be at least 1");
    }
    let pool = crate::args::thread_pool(Some(a.threads))?;
    let options = quadray_loader::ImportOptions {
        up: quadray_loader::UpAxis::Z,
        skip_materials: true,
        ..Default::default()
    };
    use quadray_loader::FileFormat;
    let imported = match FileFormat::of(&a.mesh) {
        Some(FileFormat::Obj) => quadray_loader::obj::import_obj(&a.mesh, &options)?,
        Some(FileFormat::Gltf) => quadray_loader::gltf::import_gltf(&a.mesh, &options)?,
        Some(FileFormat::Native) | None => {
            bail!("{}: expected an .obj, .gltf or .glb mesh", a.mesh.display())
        }
    };
    let name = a
        .mesh
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_string();
    let description = |geometry: Geometry| SceneDescription {
        camera: Camera::orbit(DVec3::ZERO, 0.0, 0.0, 1.0, 40.0),
        background: glam::Vec3::ZERO,
        environment: None,
        materials: vec![Material::default()],
        lights: Vec::new(),
        geometry,
    };
    let mut builds = Vec::new();
    let mut build_cpu = Vec::new();
    let mut scene = None;
    for _ in 0..a.builds {
        let geometry = imported.geometry.clone();
        let cpu = cpu_time::ProcessTime::now();
        let start = Instant::now();
        let options = quadray::BuildOptions {
            compact_meshes: a.compact_meshes,
        };
        let built = pool.install(|| Scene::build(description(geometry), options))?;
        builds.push(start.elapsed().as_secs_f64() * 1e3);
        build_cpu.push(cpu.elapsed().as_secs_f64() * 1e3);
        scene = Some(built);
    }
    let scene = scene.expect("at least one build");
    let g = scene.geometry();
    let triangles: usize = g.meshes.iter().map(|m| m.triangle_count()).sum();
    let mesh_bytes: usize = g.meshes.iter().map(|m| m.memory_bytes()).sum();
    let accel_bytes = scene.accel().memory_bytes();
    outln!(
        "BUILD mesh={name} impl=quadray threads={} triangles={triangles} ms_median={:.2} cpu_ms={:.2} \
         mesh_bytes_per_tri={:.1} accel_bytes_per_tri={:.1} bytes_per_tri={:.1} simd={} leaves={}",
        a.threads,
        median(builds),
        median(build_cpu),
        mesh_bytes as f64 / triangles.max(1) as f64,
        accel_bytes as f64 / triangles.max(1) as f64,
        (mesh_bytes + accel_bytes) as f64 / triangles.max(1) as f64,
        scene.accel().traversal_path(),
        if a.compact_meshes {
            "compact"
        } else {
            "copied"
        },
    )?;
    for path in &a.rays {
        let rays = read_rays(path)?;
        let set = path
            .file_name()
            .and_then(|s| s.to_str())
            .map(|s| s.trim_end_matches(".rays"))
            .and_then(|s| s.rsplit('.').next())
            .unwrap_or("rays")
            .to_string();
        for api in ["intersect1", "occluded1"] {
            let mut wall = Vec::new();
            let mut cpu_rates = Vec::new();
            let mut checksum = (0u64, 0.0f64);
            for _ in 0..a.runs {
                let cpu = cpu_time::ProcessTime::now();
                let start = Instant::now();
                checksum = pool.install(|| cast(&scene, &rays, api == "occluded1"));
                let secs = start.elapsed().as_secs_f64();
                wall.push(rays.len() as f64 / secs / 1e6);
                cpu_rates.push(rays.len() as f64 / cpu.elapsed().as_secs_f64() / 1e6);
            }
            outln!(
                "RESULT mesh={name} impl=quadray rays={set} api={api} threads={} mrays_median={:.3} \
                 cpu_mrays={:.3} hits={} tsum={:.6e}",
                a.threads,
                median(wall),
                median(cpu_rates),
                checksum.0,
                checksum.1
            )?;
        }
    }
    Ok(())
}

/// Casts every ray (in chunks of 4096, as the harness does) and returns the hit count and the sum
/// of the hits' t (0 for the occlusion query, which has no t).
fn cast(scene: &Scene, rays: &[Ray], occlusion: bool) -> (u64, f64) {
    let (accel, g) = (scene.accel(), scene.geometry());
    rays.par_chunks(4096)
        .map(|chunk| {
            let mut acc = (0u64, 0.0f64);
            if occlusion {
                for ray in chunk {
                    acc.0 += accel.occluded(g, ray, f64::INFINITY, None) as u64;
                }
            } else {
                for ray in chunk {
                    if let Some((t, _)) = accel.closest(g, ray, f64::INFINITY, None) {
                        acc.0 += 1;
                        acc.1 += t;
                    }
                }
            }
            acc
        })
        .reduce(|| (0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device or a folder as the ray file is refused at once (`/dev/zero` was read until
    /// memory ran out); a short file is refused by its header.
    #[test]
    fn ray_files_are_regular_files() {
        #[cfg(unix)]
        {
            let e = read_rays(Path::new("/dev/zero")).unwrap_err();
            assert!(format!("{e:#}").contains("not a regular file"), "{e:#}");
        }
        let dir = tempfile::tempdir().unwrap();
        let e = read_rays(dir.path()).unwrap_err();
        assert!(format!("{e:#}").contains("not a regular file"), "{e:#}");
        let short = dir.path().join("short.rays");
        std::fs::write(&short, b"RAYS\x02\0\0\0").unwrap();
        assert!(read_rays(&short).is_err());
    }
}
