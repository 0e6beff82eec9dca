//! How the seeded 80/20 hold-out splits of the real edge set overlap
//! (`train --val-fraction 0.2 --split-seed S`, the same shuffle as
//! `TapData::split`): `cargo run --release -p tactrace-learn --example
//! split_overlap [N]` (N = rows, default 3762).
use rand::seq::SliceRandom;
use rand::SeedableRng;
use std::collections::HashSet;

fn held_out(n: usize, seed: u64) -> HashSet<usize> {
    let mut idx: Vec<usize> = (0..n).collect();
    idx.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
    let cut = ((n as f64 * 0.8).round() as usize).min(n);
    idx[cut..].iter().copied().collect()
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("N: a row count"))
        .unwrap_or(3762);
    let tests: Vec<HashSet<usize>> = (1..=3).map(|s| held_out(n, s)).collect();
    println!(
        "{n} rows; held-out sizes {:?}",
        tests.iter().map(HashSet::len).collect::<Vec<_>>()
    );
    for a in 0..3 {
        for b in a + 1..3 {
            let shared = tests[a].intersection(&tests[b]).count();
            println!(
                "split {} and split {}: {shared} held-out rows shared; {} of split {}'s held-out rows are in split {}'s training part",
                a + 1,
                b + 1,
                tests[a].len() - shared,
                a + 1,
                b + 1
            );
        }
    }
}
