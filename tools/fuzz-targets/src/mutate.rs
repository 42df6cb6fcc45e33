//! A small deterministic mutator for the replay test's smoke run: from a
//! seed file and a fixed seed, bit flips, byte inserts and deletes, bytes
//! set to boundary values, ASCII integers replaced by boundary integers,
//! chunks duplicated, and truncation. Not a fuzzer: a few thousand cheap
//! variations of the corpus that any stable toolchain runs in seconds.

/// SplitMix64.
#[derive(Debug, Clone)]
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

const BOUNDARY_BYTES: [u8; 8] = [0, 1, 0x7f, 0x80, 0xfe, 0xff, b'\n', b' '];
const BOUNDARY_INTS: [&str; 12] = ["0", "-1", "1", "255", "256", "65535", "2147483647", "-2147483648", "4294967295", "4294967296", "18446744073709551615", "1e308"];

/// One to four random mutations of `seed`.
pub fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut d = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        match rng.below(8) {
            0 if !d.is_empty() => {
                let i = rng.below(d.len());
                d[i] ^= 1 << rng.below(8);
            }
            1 => {
                let i = rng.below(d.len() + 1);
                d.insert(i, rng.next() as u8);
            }
            2 if !d.is_empty() => {
                let i = rng.below(d.len());
                let n = 1 + rng.below(8.min(d.len() - i));
                d.drain(i..i + n);
            }
            3 if !d.is_empty() => {
                let i = rng.below(d.len());
                d[i] = BOUNDARY_BYTES[rng.below(BOUNDARY_BYTES.len())];
            }
            4 if d.len() >= 4 => {
                // A little-endian boundary integer over 4 bytes.
                let i = rng.below(d.len() - 3);
                let v: u32 = [0, 1, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 0x7f80_0000][rng.below(6)];
                d[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            5 => {
                // Replace an ASCII number by a boundary integer.
                let starts: Vec<usize> = (0..d.len()).filter(|&i| d[i].is_ascii_digit() && (i == 0 || !d[i - 1].is_ascii_digit())).collect();
                if !starts.is_empty() {
                    let i = starts[rng.below(starts.len())];
                    let j = (i..d.len()).find(|&j| !d[j].is_ascii_digit()).unwrap_or(d.len());
                    let b = BOUNDARY_INTS[rng.below(BOUNDARY_INTS.len())];
                    d.splice(i..j, b.bytes());
                }
            }
            6 if !d.is_empty() => {
                let i = rng.below(d.len());
                let n = 1 + rng.below(32.min(d.len() - i));
                let copy = d[i..i + n].to_vec();
                let at = rng.below(d.len() + 1);
                d.splice(at..at, copy);
            }
            _ if !d.is_empty() => d.truncate(rng.below(d.len())),
            _ => {}
        }
    }
    d
}
