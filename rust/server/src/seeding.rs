//! The seeds of a world's lanes, computed as the Python envs compute them, so that a world
//! seeded with `seed` gives the trajectories of `sixaxis_avoid.vector`'s `reset(seed=seed)`.
//!
//! The native vector env seeds lane `i`'s generator of random targets with
//! `gymnasium.utils.seeding.np_random(seed + i)[0].integers(0, 2**63)`: NumPy's
//! `SeedSequence(seed + i)` feeds a `PCG64` bit generator and `integers(0, 2**63)` draws one
//! int64. This module is that arithmetic, from NumPy's documented algorithms
//! (docs/SERVER.md, "Seeds"):
//! - `SeedSequence`: the entropy (the seed's 32-bit words, least significant first) is
//!   hashed into a pool of four 32-bit words, and `generate_state` hashes the pool into the
//!   words asked for;
//! - `PCG64`: a 128-bit LCG seeded with `generate_state(4, uint64)` (state, then stream),
//!   whose output is XSL-RR;
//! - `integers(0, 2**63)`: Lemire's bounded draw over `2**63` values, which for that range
//!   is the 64-bit output shifted right by one (no draw is ever rejected).

const INIT_A: u32 = 0x43b0_d7e5;
const MULT_A: u32 = 0x931e_8875;
const INIT_B: u32 = 0x8b51_f9dd;
const MULT_B: u32 = 0x58f3_8ded;
const MIX_MULT_L: u32 = 0xca01_f9dd;
const MIX_MULT_R: u32 = 0x4973_f715;
const XSHIFT: u32 = 16;
const POOL_SIZE: usize = 4;
const PCG_MULT: u128 = 0x2360_ed05_1fc6_5da4_4385_df64_9fcc_f645;

fn hashmix(value: u32, hash_const: &mut u32) -> u32 {
    let mut v = value ^ *hash_const;
    *hash_const = hash_const.wrapping_mul(MULT_A);
    v = v.wrapping_mul(*hash_const);
    v ^ (v >> XSHIFT)
}

fn mix(x: u32, y: u32) -> u32 {
    let r = MIX_MULT_L
        .wrapping_mul(x)
        .wrapping_sub(MIX_MULT_R.wrapping_mul(y));
    r ^ (r >> XSHIFT)
}

/// The entropy words of a non-negative integer: 32-bit words, least significant first
/// (`[0]` for 0).
fn entropy_words(seed: u128) -> Vec<u32> {
    let mut words = Vec::new();
    let mut s = seed;
    loop {
        words.push(s as u32);
        s >>= 32;
        if s == 0 {
            break;
        }
    }
    words
}

/// NumPy's `SeedSequence(seed).pool`.
fn pool(seed: u128) -> [u32; POOL_SIZE] {
    let entropy = entropy_words(seed);
    let mut hash_const = INIT_A;
    let mut mixer = [0u32; POOL_SIZE];
    for (i, m) in mixer.iter_mut().enumerate() {
        *m = hashmix(entropy.get(i).copied().unwrap_or(0), &mut hash_const);
    }
    for src in 0..POOL_SIZE {
        for dst in 0..POOL_SIZE {
            if src != dst {
                let h = hashmix(mixer[src], &mut hash_const);
                mixer[dst] = mix(mixer[dst], h);
            }
        }
    }
    for &e in entropy.iter().skip(POOL_SIZE) {
        for m in mixer.iter_mut() {
            let h = hashmix(e, &mut hash_const);
            *m = mix(*m, h);
        }
    }
    mixer
}

/// NumPy's `SeedSequence(seed).generate_state(n, uint64)`.
fn generate_state_u64(seed: u128, n: usize) -> Vec<u64> {
    let pool = pool(seed);
    let mut hash_const = INIT_B;
    let words: Vec<u32> = (0..2 * n)
        .map(|i| {
            let mut v = pool[i % POOL_SIZE] ^ hash_const;
            hash_const = hash_const.wrapping_mul(MULT_B);
            v = v.wrapping_mul(hash_const);
            v ^ (v >> XSHIFT)
        })
        .collect();
    words
        .chunks(2)
        .map(|w| u64::from(w[0]) | (u64::from(w[1]) << 32))
        .collect()
}

/// NumPy's `PCG64` bit generator.
struct Pcg64 {
    state: u128,
    inc: u128,
}

impl Pcg64 {
    fn from_seed_sequence(seed: u128) -> Pcg64 {
        let v = generate_state_u64(seed, 4);
        let initstate = (u128::from(v[0]) << 64) | u128::from(v[1]);
        let initseq = (u128::from(v[2]) << 64) | u128::from(v[3]);
        let mut g = Pcg64 {
            state: 0,
            inc: (initseq << 1) | 1,
        };
        g.step();
        g.state = g.state.wrapping_add(initstate);
        g.step();
        g
    }

    fn step(&mut self) {
        self.state = self.state.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
    }

    fn next_u64(&mut self) -> u64 {
        self.step();
        let s = self.state;
        let xored = ((s >> 64) as u64) ^ (s as u64);
        xored.rotate_right((s >> 122) as u32)
    }
}

/// `int(np_random(seed)[0].integers(0, 2**63))`: the seed of the core's generator of random
/// targets that the Python envs derive from a Gymnasium seed.
pub fn core_seed(seed: u128) -> u64 {
    Pcg64::from_seed_sequence(seed).next_u64() >> 1
}

/// The core seeds of `n` lanes for a world seeded with `seed`: lane `i` gets
/// [`core_seed`]`(seed + i)`, as `sixaxis_avoid.vector`'s `reset(seed=seed)`.
pub fn lane_seeds(seed: u64, n: usize) -> Vec<u64> {
    (0..n)
        .map(|i| core_seed(u128::from(seed) + i as u128))
        .collect()
}

/// Seeds for `n` lanes drawn from the operating system's entropy (a world never seeded,
/// as the Python envs' `reset()` without a seed).
pub fn entropy_seeds(n: usize) -> Vec<u64> {
    use rand::Rng;
    let mut r = rand::rng();
    (0..n).map(|_| r.random_range(0..(1u64 << 63))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values printed by NumPy 2 and Gymnasium 1 for
    /// `int(gymnasium.utils.seeding.np_random(s)[0].integers(0, 2**63))`.
    #[test]
    fn matches_numpy() {
        for (seed, want) in NUMPY_VALUES {
            assert_eq!(core_seed(*seed), *want, "seed {seed}");
        }
    }

    const NUMPY_VALUES: &[(u128, u64)] = &[
        (0, 5874934615388537135),
        (1, 4720721261117928063),
        (7, 5765488047046174021),
        (42, 7138484576005690180),
        (12345, 2096804712593481934),
        (4294967295, 2323769260371640015),
        (4294967296, 8206391887579712274),
        (1099511627779, 7135717901190316950),
        (9223372036854775808, 7483331053097795198),
        (18446744073709551615, 6272139055050500935),
    ];
}
