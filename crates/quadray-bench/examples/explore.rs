use quadray_bench::hardcases::{self, SuiteSize};
use quadray_bench::metrics::{self, Tier};
use quadray_bench::variants::Variant;
use std::time::Instant;

fn main() {
    let size = SuiteSize::TEST;
    for fam in hardcases::all(size) {
        let t0 = Instant::now();
        let refs = metrics::references(&fam, Tier::Exact);
        let te = t0.elapsed();
        let vq = metrics::variant_quadrics(&fam);
        for v in [Variant::NaiveF64, Variant::Production] {
            let t = metrics::score(&fam, &refs, &vq, v);
            println!(
                "{:16} {:18} rays {:5} amb {:4} holes {:3} phan {:3} wrong {:3} med {:.2e} max {:.2e} maxscaled {:.2e} ({:?})",
                fam.name, v.name(), t.rays, t.ambiguous, t.holes, t.phantoms, t.wrong_roots,
                metrics::quantile(&t.errors, 0.5), metrics::quantile(&t.errors, 1.0),
                metrics::quantile(&t.scaled_errors, 1.0) / metrics::U, te
            );
            if v == Variant::Production {
                for f in t.failures.iter().take(3) {
                    println!("    {:?} case {:?}", f, fam.cases[f.case]);
                }
            }
        }
        let sp = hardcases::spawned(&fam, 4, 2000, 3);
        let t0 = Instant::now();
        let refs = metrics::references(&sp, Tier::Checked);
        let te = t0.elapsed();
        let t = metrics::score(&sp, &refs, &vq, Variant::Production);
        println!("  spawned rays {} amb {} holes {} phan {} wrong {} offs {} ({:?})", t.rays, t.ambiguous, t.holes, t.phantoms, t.wrong_roots, t.offset_failures, te);
        for f in t.failures.iter().take(3) {
            println!("    {:?} case {:?}", f, sp.cases[f.case]);
        }
        if fam.name == "thin-ellipsoid" {
            for r in refs.iter().step_by(1000) {
                println!("    amb {:?}", (r.margin, r.delta, r.origin_distance, r.t(), r.dir_local));
            }
        }
    }
}
#[allow(dead_code)]
fn dbg_thin() {}
