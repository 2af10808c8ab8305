//! Load and BVH build times of the large shared OBJ meshes, on one and two threads, and memory per
//! triangle. Run with `cargo bench -p quadray-loader --bench load` (needs `../shared/assets`).
//!
//! For each mesh, the `.obj.zst` file is decompressed in memory first (not timed), then each phase
//! is timed `RUNS` times and the median printed:
//! - `tobj`: tobj's parse alone, with the loader's options (the floor for any tobj-based loader);
//! - `import`: quadray's OBJ import (tobj, MTL materials and textures, conversion to quadray
//!   meshes in world space);
//! - `bvh`: `Scene::new`, which validates the scene and builds the acceleration structure, on a
//!   rayon pool of 1 or 2 threads.
//!
//! Memory per triangle: the meshes' own bytes (`Mesh::memory_bytes`), the acceleration
//! structure's persistent bytes (`Accel::memory_bytes`: wide nodes, leaf blocks, id tables),
//! and the largest resident-set growth seen over one `Scene::new` (which also counts the build's
//! transient buffers and whatever the allocator keeps).

// The tests' helpers (the compressed assets' decoding).
#[path = "../tests/common/mod.rs"]
mod common;

use quadray::Scene;
use quadray_loader::ImportOptions;
use quadray_loader::obj::import_obj_bytes;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const RUNS: usize = 9;

fn median(mut v: Vec<Duration>) -> f64 {
    v.sort();
    v[v.len() / 2].as_secs_f64() * 1e3
}

/// Resident set size in bytes (Linux), for memory growth.
fn rss() -> Option<usize> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: usize = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096)
}

fn main() {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets/meshes");
    if !assets.is_dir() {
        eprintln!(
            "skipping: {} not found (../shared is absent)",
            assets.display()
        );
        return;
    }
    let meshes: [(&str, PathBuf); 2] = [
        ("dragon_res2", assets.join("dragon_res2.obj.zst")),
        ("kitchen", assets.join("obvhs_kitchen/kitchen.obj.zst")),
    ];
    println!("median of {RUNS} runs, milliseconds");
    println!(
        "| mesh | triangles | tobj parse | quadray import | conversion share | BVH build, 1 thread | BVH build, 2 threads | load + BVH, 1 thread | load + BVH, 2 threads | mesh bytes/tri | BVH bytes/tri | peak RSS growth of the build, bytes/tri |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (name, path) in meshes {
        let bytes = common::unzstd(&path);
        let plain = path.with_extension(""); // MTL files resolve beside the .obj name
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ignore_points: true,
            ignore_lines: true,
        };
        // tobj alone and the full import alternate, so that both see the same machine load.
        let folder = plain.parent().unwrap().to_path_buf();
        let (mut tobj_times, mut import_times) = (Vec::new(), Vec::new());
        let mut imported = None;
        for _ in 0..RUNS {
            let t = Instant::now();
            let r = tobj::load_obj_buf(&mut &bytes[..], &options, |p| {
                tobj::load_mtl(folder.join(p))
            })
            .expect("tobj parses");
            std::hint::black_box(&r);
            tobj_times.push(t.elapsed());
            drop(r);
            let t = Instant::now();
            let i = import_obj_bytes(&bytes, &plain, &ImportOptions::default()).expect("import");
            import_times.push(t.elapsed());
            imported = Some(i);
        }
        let imported = imported.unwrap();
        let triangles = imported.triangle_count();
        let mesh_bytes: usize = imported
            .geometry
            .meshes
            .iter()
            .map(|m| m.memory_bytes())
            .sum();
        let scene = quadray_loader::standalone::scene_from_import(imported, &plain, None).unwrap();
        let mut build = [0.0; 2];
        let mut rss_growth = 0usize;
        let mut accel_bytes = 0usize;
        for (k, threads) in [1usize, 2].into_iter().enumerate() {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let times: Vec<Duration> = (0..RUNS)
                .map(|_| {
                    let description = scene.description.clone();
                    let before = rss();
                    let t = Instant::now();
                    let s = pool
                        .install(|| Scene::new(description))
                        .expect("valid scene");
                    let e = t.elapsed();
                    if let (Some(b), Some(a)) = (before, rss()) {
                        rss_growth = rss_growth.max(a.saturating_sub(b));
                    }
                    accel_bytes = s.accel().memory_bytes();
                    std::hint::black_box(&s);
                    e
                })
                .collect();
            build[k] = median(times);
        }
        let (tobj_ms, import_ms) = (median(tobj_times), median(import_times));
        println!(
            "| {name} | {triangles} | {tobj_ms:.1} | {import_ms:.1} | {:.0}% | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |",
            100.0 * (import_ms - tobj_ms) / import_ms,
            build[0],
            build[1],
            import_ms + build[0],
            import_ms + build[1],
            mesh_bytes as f64 / triangles as f64,
            accel_bytes as f64 / triangles as f64,
            rss_growth as f64 / triangles as f64,
        );
    }
}
