//! Generation time of a 60 s `fires-v2` session with images (issue 4 target: at most 10 s on one core), and of
//! the same session without images.
#![allow(missing_docs)] // criterion's macros generate undocumented items

use criterion::{criterion_group, criterion_main, Criterion};
use fires_sim::{run_scenario, SimOptions};
use std::time::Duration;

fn generate(c: &mut Criterion) {
    let mut g = c.benchmark_group("generate");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    for (name, images) in [
        ("fires-v2 60 s with images", true),
        ("fires-v2 60 s blobs only", false),
    ] {
        g.bench_function(name, |b| {
            // The recording's removal (about 1800 files, 0.5 GB with images) is not timed.
            b.iter_with_large_drop(|| {
                let dir = tempfile::tempdir().expect("temporary directory");
                let opts = SimOptions {
                    images,
                    ..SimOptions::default()
                };
                run_scenario("fires-v2", 1, 60.0, dir.path(), opts).expect("simulation");
                dir
            })
        });
    }
    g.finish();
}

criterion_group!(benches, generate);
criterion_main!(benches);
