//! Sample streams indexed by dimension: the one owner of which number of a camera sample
//! drives which decision (docs/architecture.md). A camera sample's numbers depend only on (seed,
//! pixel, sample index, dimension), so a low-discrepancy sampler (Owen-scrambled Sobol)
//! drops in by implementing [`Sampler`] and nothing else changes.
//!
//! Dimension layout of one camera sample (`dim::*`):
//!
//! | dimensions | decision |
//! |---|---|
//! | 0, 1 | pixel filter offset (2D) |
//! | 2, 3 | lens position (2D) |
//! | `bounce(d) + 0` | light choice at scattering vertex `d` (1D) |
//! | `bounce(d) + 1, 2` | point on that light (2D) |
//! | `bounce(d) + 3` | BSDF lobe choice (1D) |
//! | `bounce(d) + 4, 5` | BSDF direction (2D) |
//! | `bounce(d) + 6` | Russian roulette after the bounce (1D) |
//!
//! with `bounce(d) = 4 + 7 d`, `d` counting scattering vertices from 0 at the first hit.
//! A path may skip dimensions (no roulette before `rr_depth`, a path that ends early) but
//! never asks for one out of order.
//!
//! Two samplers implement the layout, chosen by `[render] sampler` or `--sampler`:
//! [`SobolSampler`] (the default: Owen-scrambled Sobol points, padded: which sequence
//! and dimension each decision reads is [`SobolPixel`]'s table) and
//! [`IndependentSampler`] (one PCG32 stream per camera sample, the numbers of earlier
//! versions).
//!
//! ```toml
//! [render]
//! sampler = "sobol"    # sobol | independent
//! ```

use crate::sampling::{splitmix64, Rng};
use glam::Vec2;
use sobol_burley::parts::{self, Int4};

/// The dimension numbers of the layout above.
pub mod dim {
    pub const FILTER: u32 = 0;
    pub const LENS: u32 = 2;
    /// Per scattering vertex, offsets from [`bounce`].
    pub const LIGHT_CHOICE: u32 = 0;
    pub const LIGHT_POINT: u32 = 1;
    pub const LOBE_CHOICE: u32 = 3;
    pub const DIRECTION: u32 = 4;
    pub const ROULETTE: u32 = 6;
    /// Dimensions one scattering vertex uses.
    pub const PER_BOUNCE: u32 = 7;

    // The layout's dimensions of one bounce follow the lens and do not overlap the next
    // bounce's.
    const _: () = assert!(DIRECTION + 2 <= ROULETTE && ROULETTE + 1 == PER_BOUNCE);
    const _: () = assert!(LENS + 2 == 4);

    /// First dimension of scattering vertex `depth`.
    #[inline(always)]
    pub const fn bounce(depth: u32) -> u32 {
        4 + PER_BOUNCE * depth
    }
}

/// The numbers of one camera sample, by dimension (the layout above).
pub trait Sampler {
    /// Uniform in [0, 1) for dimension `dim`.
    fn get_1d(&mut self, dim: u32) -> f32;
    /// Uniform in [0, 1)² for dimensions `dim` and `dim + 1`.
    fn get_2d(&mut self, dim: u32) -> Vec2;
    /// `get_1d(dim::bounce(depth) + offset)`: the same number, which a sampler may find
    /// without looking the dimension up (`offset` a constant of [`dim`]).
    #[inline(always)]
    fn vertex_1d(&mut self, depth: u32, offset: u32) -> f32 {
        self.get_1d(dim::bounce(depth) + offset)
    }
    /// `get_2d(dim::bounce(depth) + offset)`, as [`vertex_1d`](Self::vertex_1d).
    #[inline(always)]
    fn vertex_2d(&mut self, depth: u32, offset: u32) -> Vec2 {
        self.get_2d(dim::bounce(depth) + offset)
    }
    /// The camera sample's filter and lens numbers: `get_2d(dim::FILTER)`, then
    /// `get_2d(dim::LENS)`.
    #[inline(always)]
    fn camera_2d(&mut self) -> (Vec2, Vec2) {
        let filter = self.get_2d(dim::FILTER);
        (filter, self.get_2d(dim::LENS))
    }
    /// The numbers of the sample's light subpath (integrator/connect.rs): the light's
    /// choice, the point on it (2D) and the emitted direction (2D). Outside the layout's
    /// dimensions, so asking for them changes no other number, whenever they are asked.
    fn light_path(&mut self) -> (f32, Vec2, Vec2);
    /// The numbers with which the light subpath scatters at its vertex `j` (from 1 at
    /// the first surface it lands on): the lobe choice, the direction (2D) and the
    /// roulette. Outside the layout, as [`light_path`](Self::light_path).
    fn light_vertex(&mut self, j: u32) -> (f32, Vec2, f32);
}

/// Which sampler a render uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    #[default]
    Sobol,
    Independent,
}

impl SamplerKind {
    pub const NAMES: [&'static str; 2] = ["sobol", "independent"];

    pub fn parse(s: &str) -> Option<SamplerKind> {
        match s {
            "sobol" => Some(SamplerKind::Sobol),
            "independent" => Some(SamplerKind::Independent),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Sobol => "sobol",
            SamplerKind::Independent => "independent",
        }
    }
}

/// Independent uniform numbers: one PCG32 stream per camera sample, read in dimension
/// order (which is why the layout forbids asking out of order). This is the sequence
/// renders have always used, so its pixels are those of earlier versions.
pub struct IndependentSampler {
    rng: Rng,
    /// (seed, pixel, sample), for the light subpath's own stream.
    key: (u64, u64, u64),
    /// The next dimension allowed, to check the order in debug builds.
    #[cfg(debug_assertions)]
    next_dim: u32,
}

impl IndependentSampler {
    pub fn new(seed: u64, pixel: u64, sample: u64) -> IndependentSampler {
        IndependentSampler {
            rng: Rng::for_sample(seed, pixel, sample),
            key: (seed, pixel, sample),
            #[cfg(debug_assertions)]
            next_dim: 0,
        }
    }

    #[inline(always)]
    fn check_order(&mut self, _dim: u32, _count: u32) {
        #[cfg(debug_assertions)]
        {
            debug_assert!(
                _dim >= self.next_dim,
                "dimension {_dim} asked after {}",
                self.next_dim
            );
            self.next_dim = _dim + _count;
        }
    }
}

impl Sampler for IndependentSampler {
    #[inline(always)]
    fn get_1d(&mut self, dim: u32) -> f32 {
        self.check_order(dim, 1);
        self.rng.next_f32()
    }

    #[inline(always)]
    fn get_2d(&mut self, dim: u32) -> Vec2 {
        self.check_order(dim, 2);
        self.rng.next_2d()
    }

    /// From a stream of their own (the seed hashed with a constant), not the path's.
    fn light_path(&mut self) -> (f32, Vec2, Vec2) {
        let (seed, pixel, sample) = self.key;
        let mut rng = Rng::for_sample(seed ^ LIGHT_PATH_SEED, pixel, sample);
        (rng.next_f32(), rng.next_2d(), rng.next_2d())
    }

    /// From a stream of their own per vertex, as `light_path`.
    fn light_vertex(&mut self, j: u32) -> (f32, Vec2, f32) {
        let (seed, pixel, sample) = self.key;
        let vertex_seed = LIGHT_PATH_SEED.wrapping_add(splitmix64(u64::from(j)));
        let mut rng = Rng::for_sample(seed ^ vertex_seed, pixel, sample);
        let u_lobe = rng.next_f32();
        (u_lobe, rng.next_2d(), rng.next_f32())
    }
}

/// Folded into the seed of the independent sampler's light-subpath stream.
const LIGHT_PATH_SEED: u64 = 0x6c69_6768_7470_6174;

/// Makes the samplers of one pixel's camera samples (state shared by a pixel's samples
/// is computed once per pixel).
pub trait PixelSampler {
    type Sampler<'a>: Sampler
    where
        Self: 'a;
    /// The numbers of camera sample `sample` of this pixel.
    fn sample(&mut self, sample: u64) -> Self::Sampler<'_>;
}

/// The independent sampler's pixel: its samples' streams are seeded by (seed, pixel,
/// sample).
pub struct IndependentPixel {
    seed: u64,
    pixel: u64,
}

impl IndependentPixel {
    pub fn new(seed: u64, pixel: u64) -> IndependentPixel {
        IndependentPixel { seed, pixel }
    }
}

impl PixelSampler for IndependentPixel {
    type Sampler<'a> = IndependentSampler;
    #[inline]
    fn sample(&mut self, sample: u64) -> IndependentSampler {
        IndependentSampler::new(self.seed, self.pixel, sample)
    }
}

/// Owen-scrambled Sobol points (Burley 2020, the `sobol_burley` crate), padded: a
/// camera sample's decisions are drawn from several independent Owen-scrambled Sobol
/// sequences, each seeded per pixel, so that every decision reads the sequence's first,
/// best-stratified dimensions instead of dimension 40 or 200 of one long sequence (the
/// crate's "padding" by seeds). Which decision reads which sequence:
///
/// | layout dimensions | sequence | its dimensions |
/// |---|---|---|
/// | pixel filter (2D), lens (2D) | the camera sequence | 0, 1 / 2, 3 |
/// | vertex `d`: light point (2D), light choice, lobe choice | vertex `d`'s own | 0, 1 / 2 / 3 |
/// | vertex `d`: direction (2D) | the directions sequence, one for the whole path | 2d, 2d + 1 |
/// | vertex `d`: Russian roulette | roulette `d`'s own | 0 |
///
/// So each point on a light and the first direction are (0, 2)-nets, and the directions
/// of consecutive bounces are stratified together (the indirect light of a diffuse scene
/// depends on them jointly: on cornell-classic this layout has 20 % less variance away
/// from the lamp than one 256-dimension sequence, docs/performance.md).
///
/// The numbers depend only on (seed, pixel, sample index, dimension), like the
/// independent sampler's, so sample ranges merge exactly; a range that starts and ends
/// at multiples of a power of two (0–63, 64–127, …) is itself a well-stratified point
/// set. Past the crate's 256 dimensions of the directions sequence (a path deeper than
/// 128 bounces) the directions are independent hashes of (seed, pixel, sample,
/// dimension); past its 2^16 samples per sequence, each further block of 2^16 samples
/// uses sequences of its own.
///
/// Every number is exactly `sobol_burley::sample_4d(index, set, sequence seed)` (a test
/// compares them), computed faster: the Sobol matrix is applied through tables (per
/// dimension set, the image of each nibble of the 16-bit index: four lookups instead of
/// a loop over the index's bits), and each sequence's shuffle and scramble hashes are
/// computed once per pixel. This was 17 % of a `cornell-classic` render's instructions in
/// the crate's code (see docs/performance.md).
pub struct SobolPixel {
    seed: u64,
    pixel: u64,
    /// The block of 2^16 samples the sequences are for (`u64::MAX`: none).
    block: u64,
    /// The camera sequence's seed, with the block folded in, and the hash it came from;
    /// the other sequences' seeds derive from it (`sequence_seed`, `directions_seed`).
    sequence: u32,
    block_hash: u64,
    /// The padded sequences' hashes, by sequence number (valid where `valid` has its
    /// bit).
    hashes: [SequenceHashes; CACHED_SEQUENCES],
    valid: u64,
    /// The directions sequence: its index shuffle, and per dimension set its scramble
    /// (valid where `directions_valid` has its bit).
    directions_shuffle: u32,
    directions_scrambles: [Int4; SOBOL_SETS],
    directions_valid: u64,
    tables: &'static SobolTables,
}

/// A sequence's two hashes (the crate's `sample_4d` computes them from the seed on every
/// call): the index shuffle and the first set's Owen scramble.
#[derive(Clone, Copy)]
struct SequenceHashes {
    shuffle: u32,
    scramble: Int4,
}

/// A padded sequence other than the directions one, by number: the camera's is 0,
/// vertex `d`'s `1 + 2d`, roulette `d`'s `2 + 2d`. The number is also its place in
/// `SobolPixel::hashes` (when below `CACHED_SEQUENCES`).
const CAMERA: u32 = 0;
fn vertex_sequence(d: u32) -> u32 {
    1 + 2 * d
}
fn roulette_sequence(d: u32) -> u32 {
    2 + 2 * d
}
/// The light subpath's sequences: numbers no vertex reaches (`u32::MAX` is
/// `SobolSampler::sequence`'s "none").
const LIGHT_POINT_SEQUENCE: u32 = u32::MAX - 1;
const LIGHT_DIRECTION_SEQUENCE: u32 = u32::MAX - 2;
/// Light subpath vertex `j`'s sequence (`j` ≥ 1): below the two above.
fn light_vertex_sequence(j: u32) -> u32 {
    u32::MAX - 2 - j.min(u32::MAX / 2)
}

/// A padded sequence's seed for `sobol_burley`: the camera sequence's is the pixel's
/// (so camera rays are those of renders made before padding), the others hash it with
/// their number.
fn sequence_seed(number: u32, sequence: u32) -> u32 {
    if number == CAMERA {
        sequence
    } else {
        parts::hash(sequence ^ number.wrapping_mul(0x9e37_79b9))
    }
}

/// Where a layout dimension's number comes from (`SobolPixel`'s table).
#[derive(Clone, Copy)]
enum Source {
    /// Lane `lane` of padded sequence `sequence`'s first dimension set.
    Padded { sequence: u32, lane: u8 },
    /// Dimension `k` of the directions sequence.
    Direction(u32),
}

impl Source {
    /// The table of `SobolPixel`'s documentation.
    fn of(dim: u32) -> Source {
        if dim < dim::bounce(0) {
            return Source::Padded {
                sequence: CAMERA,
                lane: dim as u8,
            };
        }
        let d = (dim - dim::bounce(0)) / dim::PER_BOUNCE;
        let vertex = |lane| Source::Padded {
            sequence: vertex_sequence(d),
            lane,
        };
        match (dim - dim::bounce(0)) % dim::PER_BOUNCE {
            dim::LIGHT_CHOICE => vertex(VERTEX_LIGHT_CHOICE),
            dim::LOBE_CHOICE => vertex(VERTEX_LOBE_CHOICE),
            dim::ROULETTE => Source::Padded {
                sequence: roulette_sequence(d),
                lane: 0,
            },
            k if k >= dim::DIRECTION => Source::Direction(2 * d + (k - dim::DIRECTION)),
            k => vertex(VERTEX_LIGHT_POINT + (k - dim::LIGHT_POINT) as u8),
        }
    }
}

impl Source {
    /// `dim`'s source if `dim + 1` reads the next lane of the same set of numbers.
    fn pair(dim: u32) -> Option<Source> {
        match (Source::of(dim), Source::of(dim + 1)) {
            (
                Source::Padded { sequence, lane },
                Source::Padded {
                    sequence: s,
                    lane: l,
                },
            ) if s == sequence && l == lane + 1 => Some(Source::Padded { sequence, lane }),
            (Source::Direction(k), Source::Direction(j))
                if j == k + 1 && k % 4 != 3 && j < SOBOL_DIMENSIONS =>
            {
                Some(Source::Direction(k))
            }
            _ => None,
        }
    }
}

/// Layout dimensions whose `Source` `SobolTables` keeps (those of the first 128
/// bounces); deeper ones are worked out on each call.
const TABLED_DIMENSIONS: u32 = dim::bounce(128);

/// The directions sequence's seed (`sequence_seed`'s counterpart).
fn directions_seed(sequence: u32) -> u32 {
    parts::hash(sequence ^ 0x5bd1_e995)
}

/// Padded sequences whose hashes a pixel keeps: the camera's and those of the first 31
/// vertices and roulettes (numbers below 64, one bit each in `SobolPixel::valid`).
const CACHED_SEQUENCES: usize = 64;

/// The numbers of one camera sample of a [`SobolPixel`].
pub struct SobolSampler<'p> {
    pixel: &'p mut SobolPixel,
    /// The sample's number, hashed with the seed and pixel for the dimensions past the
    /// crate's only when a path gets there (past 128 bounces: hardly ever, so not per
    /// sample).
    sample: u64,
    /// The index with its bits reversed, before any sequence's shuffle.
    index_rev: u32,
    /// The padded sequence whose four numbers are in `cached` (`u32::MAX`: none yet).
    sequence: u32,
    cached: [f32; 4],
    /// The directions sequence's shuffled index, and the set in `directions` (`u32::MAX`:
    /// none yet).
    directions_index: u32,
    directions_set: u32,
    directions: [f32; 4],
}

/// Dimensions of the directions sequence the Sobol sequence covers (the rest are
/// independent).
pub const SOBOL_DIMENSIONS: u32 = sobol_burley::NUM_DIMENSIONS;
const SOBOL_SETS: usize = sobol_burley::NUM_DIMENSION_SETS_4D as usize;
const _: () = assert!(
    SOBOL_SETS <= 64,
    "one bit per set in SobolPixel::directions_valid"
);

/// The lanes of a vertex's sequence: the light point takes the first two dimensions,
/// the (0, 2)-net.
const VERTEX_LIGHT_POINT: u8 = 0;
const VERTEX_LIGHT_CHOICE: u8 = 2;
const VERTEX_LOBE_CHOICE: u8 = 3;

/// Per dimension set, the Sobol matrix's image of each nibble of the (bit-reversed)
/// 16-bit index: the sequence is linear over GF(2), so the XOR of four lookups is the
/// matrix product. 1 KB per set; a path touches its first few.
pub struct SobolTables {
    sets: Vec<[[[u32; 4]; 16]; 4]>,
    /// Each layout dimension's source, below `TABLED_DIMENSIONS` (one load instead of
    /// a division and a match per number).
    sources: Vec<Source>,
    /// Per layout dimension below `TABLED_DIMENSIONS`, its source if the next dimension
    /// is the next lane of the same set (every 2D pair of the layout: filter, lens,
    /// light point, direction), so that `get_2d` looks up and checks its set once.
    pairs: Vec<Option<Source>>,
    /// Whether the CPU has SSE4.1 (`scrambled_numbers`).
    sse41: bool,
}

impl SobolTables {
    fn get() -> &'static SobolTables {
        static TABLES: std::sync::OnceLock<SobolTables> = std::sync::OnceLock::new();
        TABLES.get_or_init(|| SobolTables {
            sets: (0..SOBOL_SETS as u32)
                .map(|set| {
                    std::array::from_fn(|q| {
                        std::array::from_fn(|v| {
                            let bits = (v as u32) << (28 - 4 * q);
                            <[u32; 4]>::from(parts::sobol_int4_rev(bits, set))
                        })
                    })
                })
                .collect(),
            sources: (0..TABLED_DIMENSIONS).map(Source::of).collect(),
            pairs: (0..TABLED_DIMENSIONS).map(Source::pair).collect(),
            #[cfg(target_arch = "x86_64")]
            sse41: is_x86_feature_detected!("sse4.1"),
            #[cfg(not(target_arch = "x86_64"))]
            sse41: false,
        })
    }

    /// The unscrambled Sobol point of reversed index `index_rev` in `set`
    /// (`parts::sobol_int4_rev`, which reads the top 16 bits).
    #[inline(always)]
    fn sobol_rev(&self, index_rev: u32, set: usize) -> Int4 {
        let t = &self.sets[set];
        Int4::from(t[0][(index_rev >> 28) as usize])
            ^ Int4::from(t[1][(index_rev >> 24 & 15) as usize])
            ^ Int4::from(t[2][(index_rev >> 20 & 15) as usize])
            ^ Int4::from(t[3][(index_rev >> 16 & 15) as usize])
    }

    /// Set `set`'s four numbers for reversed index `index_rev` under Owen scramble
    /// `scramble`: `scrambled_numbers` of `sobol_rev`. With SSE4.1 the table rows are
    /// loaded inside the one call (`numbers_sse41`): the point stays in a register
    /// instead of going through memory into the call.
    #[inline(always)]
    fn numbers(&self, index_rev: u32, set: usize, scramble: Int4) -> [f32; 4] {
        #[cfg(target_arch = "x86_64")]
        if self.sse41 {
            // SAFETY: `sse41` is `is_x86_feature_detected!("sse4.1")`.
            return unsafe { numbers_sse41(&self.sets[set], index_rev, scramble.into()) };
        }
        scrambled_numbers(self.sobol_rev(index_rev, set), scramble, false)
    }
}

/// `sobol_burley::sample_4d`'s shuffle hash for a sequence seed.
#[inline(always)]
fn shuffle_hash(seed: u32) -> u32 {
    parts::hash(seed ^ 0x79c6_8e4a)
}

/// `sobol_burley::sample_4d`'s scramble of dimension set `set` for a sequence seed.
#[inline(always)]
fn scramble_hash(seed: u32, set: u32) -> Int4 {
    let seed = Int4::from([seed.wrapping_mul(0x9c8f_2d3b); 4]);
    let ds = Int4::from([set; 4]);
    let lanes = Int4::from([0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8]);
    parts::hash_int4(seed ^ ds ^ lanes)
}

impl SobolPixel {
    pub fn new(seed: u64, pixel: u64) -> SobolPixel {
        let none = SequenceHashes {
            shuffle: 0,
            scramble: Int4::from([0; 4]),
        };
        SobolPixel {
            seed,
            pixel,
            block: u64::MAX,
            sequence: 0,
            block_hash: 0,
            hashes: [none; CACHED_SEQUENCES],
            valid: 0,
            directions_shuffle: 0,
            directions_scrambles: [Int4::from([0; 4]); SOBOL_SETS],
            directions_valid: 0,
            tables: SobolTables::get(),
        }
    }

    /// This pixel made over for pixel `pixel` of seed `seed`: the same numbers as
    /// `SobolPixel::new(seed, pixel)`'s (the first sample's block differs from `block`,
    /// so it works out the hashes again), without clearing and copying its ~2.4 KB.
    pub fn reset(&mut self, seed: u64, pixel: u64) {
        self.seed = seed;
        self.pixel = pixel;
        self.block = u64::MAX;
    }

    /// Padded sequence `number`'s hashes.
    #[inline(always)]
    fn hashes(&mut self, number: u32) -> SequenceHashes {
        let make = |sequence| {
            let seed = sequence_seed(number, sequence);
            SequenceHashes {
                shuffle: shuffle_hash(seed),
                scramble: scramble_hash(seed, 0),
            }
        };
        let slot = number as usize;
        if slot >= CACHED_SEQUENCES {
            return make(self.sequence);
        }
        if self.valid >> slot & 1 == 0 {
            self.hashes[slot] = make(self.sequence);
            self.valid |= 1 << slot;
        }
        self.hashes[slot]
    }

    /// The Owen scramble of the directions sequence's dimension set `set`.
    #[inline(always)]
    fn directions_scramble(&mut self, set: usize) -> Int4 {
        if self.directions_valid >> set & 1 == 0 {
            self.directions_scrambles[set] =
                scramble_hash(directions_seed(self.sequence), set as u32);
            self.directions_valid |= 1 << set;
        }
        self.directions_scrambles[set]
    }
}

impl PixelSampler for SobolPixel {
    type Sampler<'a> = SobolSampler<'a>;

    fn sample(&mut self, sample: u64) -> SobolSampler<'_> {
        let block = sample >> 16;
        if block != self.block {
            let h = splitmix64(self.seed ^ splitmix64(self.pixel ^ block.rotate_left(40)));
            self.block = block;
            self.sequence = (h ^ (h >> 32)) as u32;
            self.block_hash = h;
            self.valid = 0;
            self.directions_valid = 0;
            self.directions_shuffle = shuffle_hash(directions_seed(self.sequence));
        }
        let index_rev = ((sample & 0xffff) as u32).reverse_bits();
        SobolSampler {
            index_rev,
            sample,
            directions_index: parts::owen_scramble_rev(index_rev, self.directions_shuffle),
            pixel: self,
            sequence: u32::MAX,
            cached: [0.0; 4],
            directions_set: u32::MAX,
            directions: [0.0; 4],
        }
    }
}

impl SobolSampler<'_> {
    /// The four numbers of padded sequence `sequence`: its first dimension set.
    #[inline(always)]
    fn padded(&mut self, sequence: u32) -> &[f32; 4] {
        if self.sequence != sequence {
            self.sequence = sequence;
            let h = self.pixel.hashes(sequence);
            let index_rev = parts::owen_scramble_rev(self.index_rev, h.shuffle);
            self.cached = self.pixel.tables.numbers(index_rev, 0, h.scramble);
        }
        &self.cached
    }

    /// The four numbers of the directions sequence's dimension set `set` (below
    /// `SOBOL_DIMENSIONS / 4`).
    #[inline(always)]
    fn directions(&mut self, set: u32) -> &[f32; 4] {
        if set != self.directions_set {
            self.directions_set = set;
            let set = set as usize;
            let scramble = self.pixel.directions_scramble(set);
            self.directions = self
                .pixel
                .tables
                .numbers(self.directions_index, set, scramble);
        }
        &self.directions
    }

    /// Dimension `k` of the directions sequence.
    #[inline(always)]
    fn direction(&mut self, k: u32) -> f32 {
        if k >= SOBOL_DIMENSIONS {
            let hash = splitmix64(self.pixel.block_hash ^ self.sample);
            let h = splitmix64(hash ^ (k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
            return (h >> 40) as f32 * (1.0 / (1u32 << 24) as f32);
        }
        self.directions(k / 4)[(k % 4) as usize]
    }

    /// Layout dimension `dim`, from the sequence and dimension `SobolPixel`'s table gives
    /// it.
    #[inline(always)]
    fn value(&mut self, dim: u32) -> f32 {
        let source = match self.pixel.tables.sources.get(dim as usize) {
            Some(&source) => source,
            None => Source::of(dim),
        };
        match source {
            Source::Padded { sequence, lane } => self.padded(sequence)[lane as usize],
            Source::Direction(k) => self.direction(k),
        }
    }

    /// Layout dimensions `dim` and `dim + 1`: from one set with one lookup where they
    /// are adjacent lanes of it (`SobolTables::pairs`), else one by one.
    #[inline(always)]
    fn pair(&mut self, dim: u32) -> Vec2 {
        let (lanes, i) = match self.pixel.tables.pairs.get(dim as usize) {
            Some(&Some(Source::Padded { sequence, lane })) => {
                (self.padded(sequence), lane as usize)
            }
            Some(&Some(Source::Direction(k))) => (self.directions(k / 4), (k % 4) as usize),
            _ => return Vec2::new(self.value(dim), self.value(dim + 1)),
        };
        Vec2::new(lanes[i], lanes[i + 1])
    }
}

/// A set's four numbers from its Sobol point and Owen scramble: exactly
/// `parts::owen_scramble_int4_rev(..).reverse_bits().to_f32_norm()`. The crate's x86-64
/// build has only SSE2, where each of the scramble's four lane products takes five
/// instructions and the bit reversal twenty; with SSE4.1 (`sse41`) they take one and
/// six (~16 % of a render's instructions were the sampler's).
#[inline(always)]
fn scrambled_numbers(sobol: Int4, scramble: Int4, sse41: bool) -> [f32; 4] {
    #[cfg(target_arch = "x86_64")]
    if sse41 {
        // SAFETY: `sse41` is `is_x86_feature_detected!("sse4.1")`.
        return unsafe { scrambled_numbers_sse41(sobol.into(), scramble.into()) };
    }
    let _ = sse41;
    parts::owen_scramble_int4_rev(sobol, scramble)
        .reverse_bits()
        .to_f32_norm()
}

/// `scrambled_numbers` with SSE4.1's lane products and SSSE3's byte shuffles: the same
/// integer operations, so the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "sse4.1")]
fn scrambled_numbers_sse41(sobol: [u32; 4], scramble: [u32; 4]) -> [f32; 4] {
    use std::arch::x86_64::__m128i;
    // SAFETY: `[u32; 4]` and `__m128i` are the same 16 bytes; any bits are valid.
    let (n, s) = unsafe {
        (
            std::mem::transmute::<[u32; 4], __m128i>(sobol),
            std::mem::transmute::<[u32; 4], __m128i>(scramble),
        )
    };
    scrambled_sse41(n, s)
}

/// `SobolTables::numbers` with SSE4.1: the Sobol point's four table rows (`sobol_rev`)
/// loaded and XORed in a register, then `scrambled_sse41`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "sse4.1")]
fn numbers_sse41(table: &[[[u32; 4]; 16]; 4], index_rev: u32, scramble: [u32; 4]) -> [f32; 4] {
    use std::arch::x86_64::*;
    let row = |q: usize| {
        let r = &table[q][(index_rev >> (28 - 4 * q) & 15) as usize];
        // SAFETY: `r` is 16 readable bytes; an unaligned load takes any address.
        unsafe { _mm_loadu_si128(r.as_ptr().cast()) }
    };
    let sobol = _mm_xor_si128(_mm_xor_si128(row(0), row(1)), _mm_xor_si128(row(2), row(3)));
    // SAFETY: as `row`'s.
    let s = unsafe { _mm_loadu_si128(scramble.as_ptr().cast()) };
    scrambled_sse41(sobol, s)
}

/// `scrambled_numbers_sse41` on registers.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "sse4.1")]
#[inline]
fn scrambled_sse41(mut n: std::arch::x86_64::__m128i, s: std::arch::x86_64::__m128i) -> [f32; 4] {
    use std::arch::x86_64::*;
    // parts::owen_scramble_int4_rev.
    n = _mm_xor_si128(n, _mm_mullo_epi32(n, _mm_set1_epi32(0x3d20_adea)));
    n = _mm_add_epi32(n, s);
    n = _mm_mullo_epi32(n, _mm_or_si128(_mm_srli_epi32(s, 16), _mm_set1_epi32(1)));
    n = _mm_xor_si128(n, _mm_mullo_epi32(n, _mm_set1_epi32(0x0552_6c56)));
    n = _mm_xor_si128(n, _mm_mullo_epi32(n, _mm_set1_epi32(0x53a2_2864)));
    // Bits reversed: each byte's through two nibble tables, then the bytes of each lane.
    let low_nibble = _mm_set1_epi32(0x0f0f_0f0f);
    let rev_high = _mm_setr_epi8(0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15);
    let rev_low = _mm_slli_epi16(rev_high, 4);
    let lo = _mm_and_si128(n, low_nibble);
    let hi = _mm_and_si128(_mm_srli_epi16(n, 4), low_nibble);
    n = _mm_or_si128(
        _mm_shuffle_epi8(rev_low, lo),
        _mm_shuffle_epi8(rev_high, hi),
    );
    let swap = _mm_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12);
    n = _mm_shuffle_epi8(n, swap);
    // parts' to_f32_norm: the top 23 bits as a float in [1, 2), minus one.
    let one_to_two = _mm_or_si128(_mm_srli_epi32(n, 9), _mm_set1_epi32(0x3f80_0000));
    let x = _mm_sub_ps(_mm_castsi128_ps(one_to_two), _mm_set1_ps(1.0));
    // SAFETY: `__m128` and `[f32; 4]` are the same 16 bytes; any bits are valid.
    unsafe { std::mem::transmute::<__m128, [f32; 4]>(x) }
}

impl Sampler for SobolSampler<'_> {
    #[inline(always)]
    fn get_1d(&mut self, dim: u32) -> f32 {
        self.value(dim)
    }

    #[inline(always)]
    fn get_2d(&mut self, dim: u32) -> Vec2 {
        self.pair(dim)
    }

    /// A vertex's numbers straight from `SobolPixel`'s table of sources, worked out for
    /// the constant `offset` (the vertex's own sequence, its roulette's, or the
    /// directions sequence), without the per-dimension lookups of `value` and `pair` and
    /// their lanes' bounds checks: ~75 instructions a vertex on the indirect box (3.9 M of
    /// 113 M). The same numbers (a test compares them).
    #[inline(always)]
    fn vertex_1d(&mut self, depth: u32, offset: u32) -> f32 {
        match offset {
            dim::LIGHT_CHOICE => self.padded(vertex_sequence(depth))[VERTEX_LIGHT_CHOICE as usize],
            dim::LOBE_CHOICE => self.padded(vertex_sequence(depth))[VERTEX_LOBE_CHOICE as usize],
            dim::ROULETTE => self.padded(roulette_sequence(depth))[0],
            _ => self.get_1d(dim::bounce(depth) + offset),
        }
    }

    #[inline(always)]
    fn vertex_2d(&mut self, depth: u32, offset: u32) -> Vec2 {
        const _: () = assert!(VERTEX_LIGHT_POINT == 0);
        match offset {
            dim::LIGHT_POINT => {
                let lanes = self.padded(vertex_sequence(depth));
                Vec2::new(lanes[0], lanes[1])
            }
            // Directions 2d and 2d + 1: lanes 0–1 or 2–3 of one set (`Source::pair`).
            dim::DIRECTION if 2 * depth + 1 < SOBOL_DIMENSIONS => {
                let lanes = self.directions(depth / 2);
                let i = (2 * (depth % 2)) as usize;
                Vec2::new(lanes[i], lanes[i + 1])
            }
            _ => self.get_2d(dim::bounce(depth) + offset),
        }
    }

    /// Two padded sequences of their own: the point on the light (lanes 0–1, a (0, 2)-net)
    /// and the light's choice (lane 2) from one, the direction (lanes 0–1) from the other.
    fn light_path(&mut self) -> (f32, Vec2, Vec2) {
        let lanes = *self.padded(LIGHT_POINT_SEQUENCE);
        let dir = self.padded(LIGHT_DIRECTION_SEQUENCE);
        (
            lanes[2],
            Vec2::new(lanes[0], lanes[1]),
            Vec2::new(dir[0], dir[1]),
        )
    }

    /// One padded sequence per vertex: the direction (lanes 0–1, a (0, 2)-net), the
    /// lobe choice (lane 2) and the roulette (lane 3).
    fn light_vertex(&mut self, j: u32) -> (f32, Vec2, f32) {
        let lanes = *self.padded(light_vertex_sequence(j));
        (lanes[2], Vec2::new(lanes[0], lanes[1]), lanes[3])
    }

    /// The camera sequence's four lanes (filter 0–1, lens 2–3: `Source::of`), without
    /// the table lookups.
    #[inline(always)]
    fn camera_2d(&mut self) -> (Vec2, Vec2) {
        let lanes = self.padded(CAMERA);
        (Vec2::new(lanes[0], lanes[1]), Vec2::new(lanes[2], lanes[3]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every number of the layout's vertex offsets for vertices `0..depths`, read by
    /// dimension (`get_1d`/`get_2d`) or by vertex (`vertex_1d`/`vertex_2d`), in the
    /// layout's order.
    fn read_vertices<S: Sampler>(s: &mut S, by_vertex: bool, depths: u32) -> Vec<Vec2> {
        let mut out = Vec::new();
        for depth in 0..depths {
            for (offset, two) in [
                (dim::LIGHT_CHOICE, false),
                (dim::LIGHT_POINT, true),
                (dim::LOBE_CHOICE, false),
                (dim::DIRECTION, true),
                (dim::ROULETTE, false),
            ] {
                let d = dim::bounce(depth) + offset;
                out.push(match (by_vertex, two) {
                    (false, true) => s.get_2d(d),
                    (false, false) => Vec2::new(s.get_1d(d), 0.0),
                    (true, true) => s.vertex_2d(depth, offset),
                    (true, false) => Vec2::new(s.vertex_1d(depth, offset), 0.0),
                });
            }
        }
        out
    }

    /// `vertex_1d` and `vertex_2d` give exactly `get_1d` and `get_2d`'s numbers, for both
    /// samplers, at every offset of the layout, for vertices past the cached sequences
    /// (31) and past the Sobol directions (128), in several blocks of 2^16 samples.
    #[test]
    fn vertex_numbers_are_the_layouts() {
        for (pixel, sample) in [(0, 0), (5, 3), (77, 64), (123, 65_537), (9, 200_003)] {
            let (mut a, mut b) = (SobolPixel::new(11, pixel), SobolPixel::new(11, pixel));
            let (by_dim, by_vertex) = (
                read_vertices(&mut a.sample(sample), false, 140),
                read_vertices(&mut b.sample(sample), true, 140),
            );
            assert_eq!(by_dim, by_vertex, "pixel {pixel}, sample {sample}");
            let (by_dim, by_vertex) = (
                read_vertices(&mut IndependentSampler::new(3, pixel, sample), false, 4),
                read_vertices(&mut IndependentSampler::new(3, pixel, sample), true, 4),
            );
            assert_eq!(
                by_dim, by_vertex,
                "independent: pixel {pixel}, sample {sample}"
            );
        }
    }

    /// A pixel made over by `reset` gives the numbers of a new one.
    #[test]
    fn a_reset_pixel_is_a_new_one() {
        let mut reused = SobolPixel::new(4, 17);
        let _ = reused
            .sample(70_000)
            .get_2d(dim::bounce(3) + dim::DIRECTION);
        for (seed, pixel, sample) in [(4, 18, 0), (5, 18, 3), (5, 19, 65_540)] {
            reused.reset(seed, pixel);
            let mut new = SobolPixel::new(seed, pixel);
            let (mut a, mut b) = (reused.sample(sample), new.sample(sample));
            for d in 0..60 {
                assert_eq!(
                    a.get_1d(d),
                    b.get_1d(d),
                    "seed {seed}, pixel {pixel}, dim {d}"
                );
            }
        }
    }

    /// `camera_2d` gives `get_2d(FILTER)` and `get_2d(LENS)`'s numbers, for both samplers,
    /// in several blocks of 2^16 samples.
    #[test]
    fn camera_numbers_are_the_layouts() {
        for (pixel, sample) in [(0, 0), (5, 3), (77, 64), (123, 65_537), (9, 200_003)] {
            let (mut a, mut b) = (SobolPixel::new(11, pixel), SobolPixel::new(11, pixel));
            let (mut sa, mut sb) = (a.sample(sample), b.sample(sample));
            let by_dim = (sa.get_2d(dim::FILTER), sa.get_2d(dim::LENS));
            assert_eq!(by_dim, sb.camera_2d(), "pixel {pixel}, sample {sample}");
            let mut ia = IndependentSampler::new(3, pixel, sample);
            let mut ib = IndependentSampler::new(3, pixel, sample);
            let by_dim = (ia.get_2d(dim::FILTER), ia.get_2d(dim::LENS));
            assert_eq!(by_dim, ib.camera_2d());
        }
    }

    /// Reading the layout in order gives exactly the stream `Rng` gives: the pixels of
    /// renders made before the sampler existed.
    #[test]
    fn independent_sampler_reads_the_rng_stream_in_order() {
        let mut rng = Rng::for_sample(7, 123, 4);
        let mut s = IndependentSampler::new(7, 123, 4);
        assert_eq!(s.get_2d(dim::FILTER), rng.next_2d());
        assert_eq!(s.get_2d(dim::LENS), rng.next_2d());
        for d in 0..3 {
            let b = dim::bounce(d);
            assert_eq!(s.get_1d(b + dim::LIGHT_CHOICE), rng.next_f32());
            assert_eq!(s.get_2d(b + dim::LIGHT_POINT), rng.next_2d());
            assert_eq!(s.get_1d(b + dim::LOBE_CHOICE), rng.next_f32());
            assert_eq!(s.get_2d(b + dim::DIRECTION), rng.next_2d());
            if d > 0 {
                assert_eq!(s.get_1d(b + dim::ROULETTE), rng.next_f32());
            }
        }
    }

    #[cfg(debug_assertions)]
    #[test]
    #[should_panic(expected = "asked after")]
    fn asking_out_of_order_is_caught() {
        let mut s = IndependentSampler::new(1, 2, 3);
        s.get_2d(dim::LENS);
        s.get_2d(dim::FILTER);
    }

    /// Owen-scrambled Sobol points stratify every dimension: the first 2^k samples of a
    /// pixel put exactly one number in each interval [j/2^k, (j+1)/2^k), in every
    /// dimension the crate covers. Independent numbers do not (checked too, so the test
    /// can tell the two apart).
    #[test]
    fn sobol_stratifies_each_dimension() {
        let n = 256u64;
        for dim in [0u32, 1, 2, 4, 5, 7, 10, 38, 100, 255] {
            for pixel in [0u64, 77, 4096] {
                let mut hit = vec![0u32; n as usize];
                for s in 0..n {
                    let x = SobolPixel::new(3, pixel).sample(s).get_1d(dim);
                    assert!((0.0..1.0).contains(&x));
                    hit[(x * n as f32) as usize] += 1;
                }
                assert!(hit.iter().all(|&h| h == 1), "dim {dim} pixel {pixel}");
            }
        }
        let mut hit = vec![0u32; n as usize];
        for s in 0..n {
            let x = IndependentSampler::new(3, 0, s).get_1d(0);
            hit[(x * n as f32) as usize] += 1;
        }
        assert!(hit.iter().any(|&h| h != 1));
    }

    /// The pixel filter's two dimensions form a (0, 2)-net: 1024 samples put one point
    /// in each cell of a 32 × 32 grid.
    #[test]
    fn sobol_filter_dimensions_form_a_net() {
        let mut cells = vec![0u32; 1024];
        for s in 0..1024 {
            let u = SobolPixel::new(9, 5).sample(s).get_2d(dim::FILTER);
            cells[(u.y * 32.0) as usize * 32 + (u.x * 32.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1));
    }

    /// Pearson's χ² over a 16 × 16 grid of 2D points (255 degrees of freedom).
    fn chi2_2d(points: impl Iterator<Item = Vec2>, n: usize) -> f64 {
        let mut cells = vec![0f64; 256];
        for u in points {
            assert!(u.x >= 0.0 && u.x < 1.0 && u.y >= 0.0 && u.y < 1.0);
            cells[(u.y * 16.0) as usize * 16 + (u.x * 16.0) as usize] += 1.0;
        }
        let e = n as f64 / 256.0;
        cells.iter().map(|c| (c - e) * (c - e) / e).sum()
    }

    /// Every 2D pair of the layout, over one pixel's samples and across pixels at one
    /// sample index, is uniform: χ² with 255 degrees of freedom below its 99.9 %
    /// quantile (330.5), for directions past the directions sequence's 256 dimensions
    /// (independent hashes) too. Within a pixel the Sobol points are far more even than random points would
    /// be (χ² far below its mean of 255).
    #[test]
    fn sobol_pairs_are_uniform_within_and_across_pixels() {
        let n = 4096;
        let mut pairs: Vec<u32> = vec![dim::FILTER, dim::LENS];
        for d in [0, 1, 5, 30] {
            let b = dim::bounce(d);
            pairs.extend([b + dim::LIGHT_POINT, b + dim::DIRECTION]);
        }
        // Light choice and lobe choice of a far vertex; the direction of a bounce past the
        // directions sequence's 256 dimensions (independent hashes).
        let far = dim::bounce(130);
        pairs.extend([far + dim::LIGHT_POINT + 1, far + dim::DIRECTION]);
        let mut pixel42 = SobolPixel::new(1, 42);
        for &d in &pairs {
            let within = chi2_2d((0..n).map(|s| pixel42.sample(s).get_2d(d)), n as usize);
            assert!(within < 330.5, "dim {d} within a pixel: chi2 {within}");
            if d != far + dim::DIRECTION {
                assert!(
                    within < 128.0,
                    "dim {d}: chi2 {within}, no better than random"
                );
            }
            let across = chi2_2d(
                (0..n).map(|p| SobolPixel::new(1, p).sample(3).get_2d(d)),
                n as usize,
            );
            assert!(across < 330.5, "dim {d} across pixels: chi2 {across}");
        }
    }

    /// Neighbouring pixels' sequences are decorrelated: the correlation of the same
    /// sample and dimension in pixels p and p + 1, over 4096 pixels, is within 4.5
    /// standard errors (1 / √n) of zero.
    #[test]
    fn sobol_pixels_are_decorrelated() {
        let n = 4096u64;
        for (dim, s) in [(0u32, 0u64), (4, 1), (8, 17), (300, 2)] {
            let v: Vec<f64> = (0..=n)
                .map(|p| SobolPixel::new(0, p).sample(s).get_1d(dim) as f64 - 0.5)
                .collect();
            let cov: f64 = v.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / n as f64;
            let corr = cov / (1.0 / 12.0);
            assert!(corr.abs() < 4.5 / (n as f64).sqrt(), "dim {dim}: {corr}");
        }
    }

    /// A sample's numbers depend only on (seed, pixel, sample, dimension): reading every
    /// dimension or skipping some gives the same numbers (so a path that ends early
    /// leaves the next sample untouched and ranges merge exactly), and a sample past
    /// the crate's 2^16 per sequence is still a valid number.
    #[test]
    fn sobol_numbers_depend_only_on_their_coordinates() {
        let all: Vec<f32> = {
            let mut px = SobolPixel::new(5, 9);
            let mut s = px.sample(70_000);
            (0..300).map(|d| s.get_1d(d)).collect()
        };
        let mut px = SobolPixel::new(5, 9);
        let mut s = px.sample(70_000);
        for d in (0..300).step_by(7) {
            assert_eq!(s.get_1d(d), all[d as usize]);
        }
        assert_ne!(
            SobolPixel::new(5, 9).sample(70_000).get_1d(0),
            SobolPixel::new(5, 9).sample(70_000 - 65_536).get_1d(0),
            "each block of 2^16 samples has its own sequence"
        );
    }

    /// The crate's number for layout dimension `dim` of sample `index` of a pixel whose
    /// camera sequence has seed `sequence`, by the table of `SobolPixel`'s documentation,
    /// written out here apart from the sampler's code (`None`: past the crate's
    /// dimensions, an independent hash).
    fn crate_number(sequence: u32, index: u32, dim: u32) -> Option<f32> {
        if dim < 4 {
            return Some(sobol_burley::sample_4d(index, 0, sequence)[dim as usize]);
        }
        let (d, offset) = ((dim - 4) / 7, (dim - 4) % 7);
        let own = |slot: u32, lane: usize| {
            let seed = parts::hash(sequence ^ slot.wrapping_mul(0x9e37_79b9));
            sobol_burley::sample_4d(index, 0, seed)[lane]
        };
        Some(match offset {
            0 => own(1 + 2 * d, 2),
            1 | 2 => own(1 + 2 * d, offset as usize - 1),
            3 => own(1 + 2 * d, 3),
            4 | 5 => {
                let k = 2 * d + offset - 4;
                if k >= 256 {
                    return None;
                }
                let seed = parts::hash(sequence ^ 0x5bd1_e995);
                sobol_burley::sample_4d(index, k / 4, seed)[k as usize % 4]
            }
            _ => own(2 + 2 * d, 0),
        })
    }

    /// The table-driven computation gives exactly the crate's `sample_4d` numbers of the
    /// padded sequences, for the sequence seed a pixel's block hashes to, across blocks
    /// of 2^16 samples, past the vertices whose hashes a pixel keeps and the bounces the
    /// directions sequence covers, with dimensions read in any order (the caches).
    #[test]
    fn sobol_tables_give_the_crates_numbers() {
        let dims = 4 + 7 * 140;
        for (seed, pixel) in [(0u64, 0u64), (7, 12_345), (u64::MAX, 99)] {
            let mut px = SobolPixel::new(seed, pixel);
            for sample in [0u64, 1, 2, 3, 63, 64, 1000, 65_535, 65_536, 70_001, 200_000] {
                let block = sample >> 16;
                let h = splitmix64(seed ^ splitmix64(pixel ^ block.rotate_left(40)));
                let sequence = (h ^ (h >> 32)) as u32;
                let index = (sample & 0xffff) as u32;
                let mut s = px.sample(sample);
                let mut compared = 0;
                for dim in (0..dims).rev().step_by(3).chain(0..dims) {
                    let got = s.get_1d(dim);
                    if let Some(want) = crate_number(sequence, index, dim) {
                        assert_eq!(
                            got, want,
                            "seed {seed} pixel {pixel} sample {sample} dim {dim}"
                        );
                        compared += 1;
                    }
                }
                assert!(compared > dims as usize, "most dimensions are Sobol");
            }
        }
    }

    /// `get_2d` reads each pair from one set where it can (`SobolTables::pairs`): the
    /// same numbers as two `get_1d`, for every layout dimension, the tabled and the
    /// deeper ones, inside and past the directions sequence's dimensions.
    #[test]
    fn sobol_pairs_are_their_two_numbers() {
        let mut px = SobolPixel::new(11, 3);
        for sample in [0u64, 5, 1000] {
            for dim in 0..dim::bounce(140) {
                let pair = px.sample(sample).get_2d(dim);
                let mut s = px.sample(sample);
                let (x, y) = (s.get_1d(dim), s.get_1d(dim + 1));
                assert_eq!((pair.x, pair.y), (x, y), "sample {sample} dim {dim}");
            }
        }
    }

    /// Every point on a light, at any bounce, and the first bounce's direction are
    /// (0, 2)-nets (the first two dimensions of their sequences): 1024 samples put one
    /// point in each cell of a 32 × 32 grid.
    #[test]
    fn sobol_light_points_and_first_direction_form_nets() {
        let mut pairs = vec![dim::bounce(0) + dim::DIRECTION];
        for d in [0, 1, 7, 40] {
            pairs.push(dim::bounce(d) + dim::LIGHT_POINT);
        }
        for d in pairs {
            let mut px = SobolPixel::new(4, 17);
            let mut cells = vec![0u32; 1024];
            for s in 0..1024 {
                let u = px.sample(s).get_2d(d);
                cells[(u.y * 32.0) as usize * 32 + (u.x * 32.0) as usize] += 1;
            }
            assert!(cells.iter().all(|&c| c == 1), "dimensions {d}, {}", d + 1);
        }
    }

    /// Both ways of making a set's numbers agree bit for bit, on random points and
    /// scrambles (the SSE4.1 one is what `sobol_tables_give_the_crates_numbers` checks
    /// on CPUs that have it).
    #[test]
    fn scrambled_numbers_are_the_crates_on_every_path() {
        let mut rng = Rng::for_sample(3, 4, 5);
        for _ in 0..20_000 {
            let sobol: [u32; 4] = std::array::from_fn(|_| rng.next_u32());
            let scramble: [u32; 4] = std::array::from_fn(|_| rng.next_u32());
            let want = parts::owen_scramble_int4_rev(sobol.into(), scramble.into())
                .reverse_bits()
                .to_f32_norm();
            for sse41 in [false, SobolTables::get().sse41] {
                let got = scrambled_numbers(sobol.into(), scramble.into(), sse41);
                assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits));
            }
        }
    }

    /// What the sampler is for: the mean of a smooth 4D integrand over 64 samples has a
    /// far smaller error with Sobol points than with independent ones (measured over 200
    /// pixels; Owen-scrambled Sobol converges as n^-1.5 or better for smooth integrands,
    /// random points as n^-0.5): over the pixel filter and lens, and over the directions
    /// of two consecutive bounces (one sequence for the whole path's directions).
    #[test]
    fn sobol_integrates_smooth_functions_with_less_error() {
        let f = |a: Vec2, b: Vec2| (a.x * a.y + b.x * b.x + (3.0 * b.y).sin()) as f64;
        let exact = 0.25 + 1.0 / 3.0 + (1.0 - 3f64.cos()) / 3.0;
        let mse = |sobol: bool, (a, b): (u32, u32)| {
            (0..200u64)
                .map(|p| {
                    let mut px = SobolPixel::new(2, p);
                    let mean = (0..64u64)
                        .map(|s| {
                            if sobol {
                                let mut x = px.sample(s);
                                f(x.get_2d(a), x.get_2d(b))
                            } else {
                                let mut x = IndependentSampler::new(2, p, s);
                                f(x.get_2d(a), x.get_2d(b))
                            }
                        })
                        .sum::<f64>()
                        / 64.0;
                    (mean - exact).powi(2)
                })
                .sum::<f64>()
                / 200.0
        };
        let direction = |d| dim::bounce(d) + dim::DIRECTION;
        for dims in [
            (dim::FILTER, dim::LENS),
            (direction(0), direction(1)),
            (direction(4), direction(5)),
        ] {
            let (sobol, independent) = (mse(true, dims), mse(false, dims));
            assert!(
                sobol < independent / 20.0,
                "{dims:?}: {sobol} vs {independent}"
            );
        }
    }
}
