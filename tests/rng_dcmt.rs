//! dcmt against published parameter sets, plus independent checks of the
//! period and of the equidistribution the tempering achieves.

use gpuwars::kernels::rng::{Mt607, Mt607Params};
use gpuwars::sim::rng::dcmt::{self, Creator};

/// Records 0..32 of `data/MersenneTwister.dat` in the GitHub repository
/// denglide/CudaDsmc (commit 9e2be03), the binary parameter file of
/// Podlozhnyuk's CUDA SDK Mersenne Twister sample format (16-byte records
/// `matrix_a, mask_b, mask_c, seed`, little endian; 65536 records, seed
/// words zero). Its include/MersenneTwister.h gives `DCMT_SEED 4172` and
/// `MT_RNG_PERIOD 607`, i.e. init_dc(4172) and get_mt_parameter_id(32, 607,
/// id) for id = 0, 1, 2, ...
const DAT_FIRST: [(u32, u32, u32); 32] = [
    (0xe98e0000, 0xddee7380, 0x6f7a8000),
    (0xf03e0001, 0x32f77780, 0xef658000),
    (0xc7e10002, 0x93d4bb80, 0xf7558000),
    (0x9c8f0003, 0x9d5f5c80, 0x77db8000),
    (0xa4660004, 0xb694f780, 0xef578000),
    (0xeef40005, 0x75de7680, 0xedd58000),
    (0x97130006, 0x3554f680, 0xedd58000),
    (0xd1a30007, 0xc5d56f80, 0xee458000),
    (0xb23b0008, 0x9c9c6b80, 0xef578000),
    (0x846d0009, 0x236d7780, 0xed758000),
    (0xf2e9000a, 0x2b7d6f80, 0xee558000),
    (0xf576000b, 0xd3fd6d80, 0x6f558000),
    (0xde40000c, 0xadb7bb80, 0x7b5b8000),
    (0xb753000d, 0x26657980, 0xf7d38000),
    (0xe197000e, 0x9cac7380, 0xeff78000),
    (0x9a27000f, 0xd9e57580, 0x77558000),
    (0xdbf80010, 0xcf777780, 0xed658000),
    (0x9f3c0011, 0xced4f680, 0xede58000),
    (0x8fb10012, 0xdcd2db80, 0xf7978000),
    (0xf35f0013, 0x679b7a80, 0xefd58000),
    (0xcc810014, 0xb5d55b80, 0x7b558000),
    (0x9faf0015, 0x9d9d6d80, 0x6fd58000),
    (0xddcc0016, 0x62566a80, 0xefd58000),
    (0xf4a90017, 0xecf35580, 0x77558000),
    (0xf5d90018, 0x655f7780, 0xf7b58000),
    (0xebb60019, 0x31ad7b80, 0xe7758000),
    (0xca99001a, 0x5cda7680, 0xedd58000),
    (0xab51001b, 0xcdddba80, 0x7bf58000),
    (0xf1f0001c, 0x9ce57380, 0x77558000),
    (0xe70f001d, 0x236d7780, 0xed758000),
    (0xda6c001e, 0xb957bb80, 0x77938000),
    (0x8d55001f, 0x5c6af680, 0xedd58000),
];

/// Later records of the same file (record index = id). Id 427 has a tie
/// list of 5760 masks, beyond the stored capacity, so it also covers the
/// regenerating walk.
const DAT_LATER: [(u16, (u32, u32, u32)); 7] = [
    (100, (0xe95e0064, 0xbcdaef80, 0xed518000)),
    (427, (0xc06a01ab, 0x9cd56b80, 0x6f558000)),
    (1000, (0xe5b403e8, 0x5d54f780, 0xeed58000)),
    (4095, (0xd1a20fff, 0x9c9c6b80, 0xef5b8000)),
    (4096, (0xedd01000, 0xd2f77b00, 0xe7d38000)),
    (20000, (0xd3764e20, 0x656d7b80, 0xebe58000)),
    (65535, (0x827affff, 0xd9557780, 0x6e578000)),
];

fn params((a, b, c): (u32, u32, u32)) -> Mt607Params {
    Mt607Params::new(a, b, c)
}

/// The first ids are cheap enough for debug builds.
#[test]
fn first_ids_match_published_file() {
    let mut creator = Creator::new(4172);
    for (id, &want) in DAT_FIRST.iter().enumerate().take(3) {
        assert_eq!(creator.parameters(id as u16), params(want), "id {id}");
    }
}

/// Each call continues dcmt's MT19937 stream, so this checks the whole
/// sequence of draws (~0.2 s per id in release).
#[test]
#[cfg_attr(debug_assertions, ignore = "slow without optimisation")]
fn id_sequence_matches_published_file() {
    let mut creator = Creator::new(4172);
    for (id, &want) in DAT_FIRST.iter().enumerate() {
        assert_eq!(creator.parameters(id as u16), params(want), "id {id}");
    }
}

/// The tempering search alone is deterministic in `matrix_a`.
#[test]
#[cfg_attr(debug_assertions, ignore = "slow without optimisation")]
fn tempering_of_later_ids_matches_published_file() {
    for &(id, want) in &DAT_LATER {
        assert_eq!(want.0 & 0xffff, u32::from(id));
        assert_eq!(dcmt::tempering_parameters(want.0), params(want), "id {id}");
    }
}

#[test]
fn try_parameters_agrees() {
    let mut a = Creator::new(1);
    let mut b = Creator::new(1);
    assert_eq!(a.try_parameters(7), Some(b.parameters(7)));
}

// --- Independent GF(2) arithmetic -----------------------------------------

const P: usize = 607;
/// 64-bit words for a polynomial of degree < 640 / a 607-bit row.
const WORDS: usize = 10;
type Row = [u64; WORDS];

fn get(r: &[u64], i: usize) -> bool {
    (r[i / 64] >> (i % 64)) & 1 == 1
}

fn flip(r: &mut [u64], i: usize) {
    r[i / 64] ^= 1 << (i % 64);
}

fn xor_into(dst: &mut Row, src: &Row) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d ^= s;
    }
}

/// Berlekamp–Massey over GF(2): the connection polynomial (coefficient list)
/// of the shortest LFSR generating `s`.
fn berlekamp_massey(s: &[bool]) -> Vec<bool> {
    let mut c = vec![false; s.len() + 1];
    let mut b = c.clone();
    c[0] = true;
    b[0] = true;
    let (mut l, mut m) = (0usize, 1usize);
    for n in 0..s.len() {
        let mut d = s[n];
        for i in 1..=l {
            d ^= c[i] & s[n - i];
        }
        if !d {
            m += 1;
            continue;
        }
        let t = c.clone();
        for i in 0..=s.len() - m {
            c[i + m] ^= b[i];
        }
        if 2 * l <= n {
            l = n + 1 - l;
            b = t;
            m = 1;
        } else {
            m += 1;
        }
    }
    c.truncate(l + 1);
    c
}

/// For a degree-607 polynomial f, whether t^(2^607) = t mod f. Then f
/// divides t^(2^607) - t, whose factors have degree 1 or 607, so f is
/// irreducible; 2^607 - 1 being prime, it is then primitive.
fn is_primitive_607(f: &[bool]) -> bool {
    assert_eq!(f.len(), P + 1);
    // t^k mod f for k in 607..1214, to reduce products quickly.
    let mut reduce = vec![[0u64; WORDS]; P];
    let mut cur = [0u64; WORDS];
    for (i, &bit) in f.iter().enumerate().take(P) {
        if bit {
            flip(&mut cur, i);
        }
    }
    for slot in reduce.iter_mut() {
        *slot = cur;
        // cur *= t, then t^607 = (f minus its leading term).
        let top = get(&cur, P - 1);
        let mut carry = 0;
        for w in cur.iter_mut() {
            let next = *w >> 63;
            *w = (*w << 1) | carry;
            carry = next;
        }
        if top {
            flip(&mut cur, P);
            for (i, &bit) in f.iter().enumerate().take(P) {
                if bit {
                    flip(&mut cur, i);
                }
            }
        }
    }
    let mut x = [0u64; WORDS];
    flip(&mut x, 1);
    for _ in 0..P {
        let mut sq = [0u64; 2 * WORDS];
        for i in 0..P {
            if get(&x, i) {
                flip(&mut sq, 2 * i);
            }
        }
        let mut r = [0u64; WORDS];
        r.copy_from_slice(&sq[..WORDS]);
        // Clear bits >= 607 of the low part and fold every high bit in.
        for i in P..WORDS * 64 {
            if get(&r, i) {
                flip(&mut r, i);
            }
        }
        for i in P..2 * P {
            if get(&sq, i) {
                xor_into(&mut r, &reduce[i - P]);
            }
        }
        x = r;
    }
    let mut t = [0u64; WORDS];
    flip(&mut t, 1);
    x == t
}

/// One MT607 step done symbolically: every bit is a linear form in the 607
/// initial state bits (bit 0 of word 0 takes no part in the recurrence).
struct Symbolic {
    words: Vec<[Row; 32]>,
}

impl Symbolic {
    fn new() -> Self {
        let mut words = vec![[[0u64; WORDS]; 32]; 19];
        let mut var = 0;
        for (w, word) in words.iter_mut().enumerate() {
            for (bit, row) in word.iter_mut().enumerate() {
                if w == 0 && bit == 0 {
                    continue;
                }
                flip(row, var);
                var += 1;
            }
        }
        assert_eq!(var, P);
        Symbolic { words }
    }

    /// Appends the next word of the sequence.
    fn extend(&mut self, a: u32) {
        let k = self.words.len() - 19;
        let (x0, x1, xm) = (self.words[k], self.words[k + 1], self.words[k + 9]);
        // y = upper 31 bits of x0 | bit 0 of x1
        let mut y = x0;
        y[0] = x1[0];
        let mut new = xm;
        for j in 0..31 {
            xor_into(&mut new[j], &y[j + 1]);
        }
        for (j, row) in new.iter_mut().enumerate() {
            if (a >> j) & 1 == 1 {
                xor_into(row, &y[0]);
            }
        }
        self.words.push(new);
    }

    /// Tempered output for word `k` of the sequence (from 19 on).
    fn output(&self, k: usize, p: &Mt607Params) -> [Row; 32] {
        let mut x = self.words[k];
        let shr = |x: &[Row; 32], s: usize| {
            let mut r = *x;
            for j in 0..32 - s {
                xor_into(&mut r[j], &x[j + s]);
            }
            r
        };
        let shl_mask = |x: &[Row; 32], s: usize, mask: u32| {
            let mut r = *x;
            for j in s..32 {
                if (mask >> j) & 1 == 1 {
                    xor_into(&mut r[j], &x[j - s]);
                }
            }
            r
        };
        x = shr(&x, 12);
        x = shl_mask(&x, 7, p.mask_b);
        x = shl_mask(&x, 15, p.mask_c);
        shr(&x, 18)
    }
}

/// Dimension of equidistribution to `v` bits by plain Gaussian elimination:
/// the largest k for which the top v bits of k consecutive outputs are
/// linearly independent functions of the state.
fn equidistribution_by_rank(outputs: &[[Row; 32]], v: usize) -> usize {
    let mut basis: Vec<Option<Row>> = vec![None; P];
    for (k, out) in outputs.iter().enumerate() {
        for bit in (32 - v..32).rev() {
            let mut row = out[bit];
            loop {
                let Some(top) = (0..P).rev().find(|&i| get(&row, i)) else {
                    return k;
                };
                match &basis[top] {
                    Some(b) => xor_into(&mut row, b),
                    None => {
                        basis[top] = Some(row);
                        break;
                    }
                }
            }
        }
    }
    outputs.len()
}

fn symbolic_outputs(p: &Mt607Params, count: usize) -> Vec<[Row; 32]> {
    let mut s = Symbolic::new();
    (0..count)
        .map(|k| {
            s.extend(p.matrix_a);
            s.output(19 + k, p)
        })
        .collect()
}

/// Parameters found for seeds other than the published one, checked only
/// structurally.
#[test]
#[cfg_attr(debug_assertions, ignore = "slow without optimisation")]
fn found_parameters_have_full_period() {
    let mut creator = Creator::new(20_240_607);
    let mut sets: Vec<Mt607Params> = (0..3).map(|id| creator.parameters(id)).collect();
    sets.extend(DAT_FIRST[..3].iter().map(|&t| params(t)));
    for p in sets {
        assert_eq!(p.matrix_a & 0x8000_0000, 0x8000_0000);
        // Any output bit satisfies the recurrence; its shortest LFSR has the
        // characteristic polynomial's degree only if that is irreducible.
        let mut g = Mt607::new(p, 12345);
        let bits: Vec<bool> = (0..2 * P + 50).map(|_| g.next_u32() & 1 == 1).collect();
        let lfsr = berlekamp_massey(&bits);
        assert_eq!(lfsr.len() - 1, P, "{p:x?}: linear complexity");
        assert!(is_primitive_607(&lfsr), "{p:x?}: not primitive");
    }
}

/// A reducible recurrence must fail the same check (guards the checker).
#[test]
#[cfg_attr(debug_assertions, ignore = "slow without optimisation")]
fn primitivity_check_rejects_other_matrix() {
    // Same id bits but a different, not-searched upper half.
    let p = Mt607Params::new(0x8000_0000, 0, 0);
    let mut g = Mt607::new(p, 1);
    let bits: Vec<bool> = (0..2 * P + 50).map(|_| g.next_u32() & 1 == 1).collect();
    let lfsr = berlekamp_massey(&bits);
    assert!(lfsr.len() - 1 != P || !is_primitive_607(&lfsr));
}

/// dcmt's lattice method agrees with Gaussian elimination, and the masks
/// reach a good share of the bound floor(607 / v).
#[test]
#[cfg_attr(debug_assertions, ignore = "slow without optimisation")]
fn equidistribution_matches_rank_computation() {
    for &t in DAT_FIRST.iter().take(3) {
        let p = params(t);
        let outputs = symbolic_outputs(&p, P + 1);
        let mut deficit = 0;
        for v in 1..=32 {
            let by_rank = equidistribution_by_rank(&outputs, v);
            let by_lattice = dcmt::equidistribution(&p, v as u32) as usize;
            assert_eq!(by_lattice, by_rank, "{p:x?} v = {v}");
            assert!(by_rank <= P / v);
            deficit += P / v - by_rank;
        }
        // Untempered (masks zero) for comparison: tempering must help.
        let plain = Mt607Params::new(p.matrix_a, 0, 0);
        let plain_outputs = symbolic_outputs(&plain, P + 1);
        let plain_deficit: usize = (1..=32)
            .map(|v| P / v - equidistribution_by_rank(&plain_outputs, v))
            .sum();
        eprintln!("{p:x?}: total deficit {deficit} (untempered {plain_deficit})");
        assert!(deficit < plain_deficit);
    }
}
