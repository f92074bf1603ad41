//! Seeded random numbers for the layout: SplitMix64, small, fast and fully
//! reproducible across platforms (method-reference §10 item 15 leaves the PRNG
//! open; parity with the prototype's Alea is not worth a dependency).

/// SplitMix64 generator (Steele, Lea and Flood 2014).
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// A generator for one named diagram: the run seed mixed with the node's id,
    /// so a diagram's random start does not depend on how many other diagrams
    /// exist or in which order (parallel) workers reach them.
    pub fn for_key(seed: u64, key: &str) -> Self {
        // FNV-1a over the id bytes, then one SplitMix round to spread it.
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in key.as_bytes() {
            h ^= u64::from(*b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        let mut r = Self::new(seed ^ h.rotate_left(17));
        r.next_u64();
        r
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A float uniform in `[0, 1)` with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_stream_and_range() {
        let mut a = Rng::new(7);
        let mut b = Rng::new(7);
        for _ in 0..1000 {
            let x = a.next_f64();
            assert_eq!(x, b.next_f64());
            assert!((0.0..1.0).contains(&x));
        }
        assert_ne!(
            Rng::for_key(1, "a").next_u64(),
            Rng::for_key(1, "b").next_u64()
        );
        assert_ne!(
            Rng::for_key(1, "a").next_u64(),
            Rng::for_key(2, "a").next_u64()
        );
    }
}
