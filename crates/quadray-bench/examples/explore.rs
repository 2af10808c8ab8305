//! Runs the accuracy report at a small size and writes the table and plot to /tmp (a quick look
//! while developing; `quadray bench accuracy` is the real command).
use quadray_bench::hardcases::SuiteSize;
use quadray_bench::report::{self, Settings};

fn main() {
    let settings = Settings {
        size: SuiteSize {
            rays: 200,
            seed: 11,
        },
        runs: 5,
        acne_hits: 2,
        acne_dirs: 2000,
    };
    let r = report::run(&settings, &mut |f| eprintln!("{f}"));
    println!("{}", r.markdown());
    r.write_svg(std::path::Path::new("/tmp/accuracy.svg"))
        .unwrap();
}
