//! The small seeded generators the workspace writes by hand, written once.
//!
//! Two algorithms, kept apart because seeded outputs depend on their exact sequences
//! (synthetic scenes, RANSAC, test data): [`SplitMix64`] (Steele, Lea & Flood 2014; its
//! finaliser is [`splitmix64`]) and [`XorShift64Star`] (Vigna 2016, shifts 12/25/27).
//! Neither is cryptographic; `rand`/`rand_chacha` stay the choice for anything drawn from
//! a distribution.

/// SplitMix64's increment (the golden ratio in 64 bits).
const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output for state `z` before the increment: `z + γ` mixed. A well-mixed
/// 64-bit hash; `SplitMix64::new(z).next_u64() == splitmix64(z)`.
#[inline]
pub fn splitmix64(z: u64) -> u64 {
    let mut z = z.wrapping_add(GOLDEN_GAMMA);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// SplitMix64: any seed (0 included) gives a full-period sequence.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator whose first output is `splitmix64(seed)`.
    pub const fn new(seed: u64) -> Self {
        SplitMix64 { state: seed }
    }

    /// The next 64 bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let out = splitmix64(self.state);
        self.state = self.state.wrapping_add(GOLDEN_GAMMA);
        out
    }

    /// `next_u64() % n` (slightly biased for large `n`, as the copies it replaces were);
    /// 0 for `n == 0`.
    #[inline]
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64().checked_rem(n).unwrap_or(0)
    }
}

/// xorshift64* (shifts 12, 25, 27; multiplier `0x2545F4914F6CDD1D`). A seed of 0, which
/// would stay 0 for ever, is taken as 1.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct XorShift64Star {
    state: u64,
}

impl XorShift64Star {
    /// A generator seeded with `seed` (0 taken as 1).
    pub const fn new(seed: u64) -> Self {
        XorShift64Star {
            state: if seed == 0 { 1 } else { seed },
        }
    }

    /// The next 64 bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.state ^= self.state >> 12;
        self.state ^= self.state << 25;
        self.state ^= self.state >> 27;
        self.state.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// The high 32 bits of the next output.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }

    /// Uniform in [0, 1): the top 53 bits of the next output.
    #[inline]
    pub fn unit_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [`lo`, `hi`).
    #[inline]
    pub fn range_f64(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit_f64()
    }

    /// The top 53 bits of the next output modulo `n`; 0 for `n == 0`.
    #[inline]
    pub fn below(&mut self, n: u64) -> u64 {
        (self.next_u64() >> 11).checked_rem(n).unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_matches_the_reference_sequence() {
        // Reference values of splitmix64.c (Vigna) seeded with 1234567.
        let mut g = SplitMix64::new(1_234_567);
        let want = [
            6_457_827_717_110_365_317,
            3_203_168_211_198_807_973,
            9_817_491_932_198_370_423,
            4_593_380_528_125_082_431,
            16_408_922_859_458_223_821,
        ];
        for w in want {
            assert_eq!(g.next_u64(), w);
        }
        assert_eq!(SplitMix64::new(7).next_u64(), splitmix64(7));
    }

    #[test]
    fn xorshift64star_steps_as_written_and_never_sticks_at_zero() {
        let mut g = XorShift64Star::new(0);
        let mut s: u64 = 1;
        for _ in 0..100 {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            assert_eq!(g.next_u64(), s.wrapping_mul(0x2545_F491_4F6C_DD1D));
        }
        assert_ne!(XorShift64Star::new(0).next_u64(), 0);
    }

    #[test]
    fn unit_below_and_range_stay_in_bounds() {
        let mut g = XorShift64Star::new(42);
        let mut h = SplitMix64::new(42);
        let mut sum = 0.0;
        for _ in 0..10_000 {
            let u = g.unit_f64();
            assert!((0.0..1.0).contains(&u));
            sum += u;
            assert!(g.below(7) < 7);
            assert!(h.below(7) < 7);
            let r = g.range_f64(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&r));
        }
        assert!((sum / 10_000.0 - 0.5).abs() < 0.02, "{sum}");
        assert_eq!(g.below(0), 0);
        assert_eq!(h.below(0), 0);
    }
}
