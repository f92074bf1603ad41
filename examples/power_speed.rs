//! Timing of `power_diagram` on 1,000 / 10,000 / 100,000 seeded random sites with
//! random weights; prints milliseconds per diagram. Not a test (no timing in
//! tests): run with `cargo run --release --example power_speed`. Owns only this
//! example; touches no library code.

use std::time::Instant;

use nptreemap::geom::{ConvexPolygon, Point};
use nptreemap::power::{power_diagram, Site};

/// SplitMix64: a tiny seeded generator, enough to place sites.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let clip = ConvexPolygon::rectangle(0.0, 0.0, 1600.0, 1000.0)?;
    println!("threads: {}", rayon::current_num_threads());
    for (n, reps) in [(1_000usize, 200usize), (10_000, 40), (100_000, 5)] {
        let mut rng = SplitMix64(0x5EED ^ n as u64);
        // Weights up to a quarter of the mean cell area: a realistic spread
        // for a treemap mid-optimisation, with a few dominated sites.
        let wmax = 0.25 * clip.area() / n as f64;
        let sites: Vec<Site> = (0..n)
            .map(|_| Site {
                position: Point::new(1600.0 * rng.next_f64(), 1000.0 * rng.next_f64()),
                weight: wmax * rng.next_f64(),
            })
            .collect();
        let _warm = power_diagram(&sites, &clip);
        let mut empty = 0;
        let mut total = 0.0;
        let mut best = f64::INFINITY;
        for _ in 0..reps {
            let start = Instant::now();
            let d = power_diagram(&sites, &clip);
            let ms = start.elapsed().as_secs_f64() * 1e3;
            total += ms;
            best = best.min(ms);
            empty = d.cells.iter().filter(|c| c.polygon.is_none()).count();
        }
        let ms = total / reps as f64;
        let d = power_diagram(&sites, &clip);
        let check = d.sanity_check(&sites, &clip);
        println!(
            "{n:>7} sites: {ms:8.2} ms per diagram (best {best:.2} ms; {empty} empty cells, sanity {check:?})"
        );
    }
    Ok(())
}
