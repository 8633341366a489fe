//! The ranges of the commands' numeric flags, checked as clap parses them (a value outside is a usage error that
//! names the flag, exit code 2), so a flag can neither abort the process with a huge allocation nor reach the
//! simulator or the trainer as a number it cannot use. A flag that overrides a scenario key or a hyperparameter
//! takes that key's range (`mapc_scenario::ranges`, `mapc_rl::limits`).

use std::ops::RangeInclusive;
use std::str::FromStr;

use clap::builder::{RangedU64ValueParser, TypedValueParser};
use mapc_scenario::ranges::{Range, show};

/// The most seeds one command runs (`--seeds`): a thousand times the usual 100, and few enough that their
/// per-seed results fit in memory.
pub const MAX_SEEDS: u64 = 100_000;
/// The largest `--first-seed`: the last seed of `MAX_SEEDS` from it still fits in 64 bits.
pub const MAX_FIRST_SEED: u64 = u64::MAX - MAX_SEEDS;
/// The most worker threads (`--threads`).
pub const MAX_THREADS: u64 = 1024;
/// The widest or tallest picture (`--width`, `--height`), pixels.
pub const MAX_PIXELS: u64 = 20_000;
/// A lane index (`--lane`): below the most lanes a road may have.
pub const LANE_INDEX: RangeInclusive<u64> = 0..=(mapc_scenario::ranges::LANES.hi as u64 - 1);
/// A demand or a flow in veh/h given on the command line: a number, not negative (a window's own check then holds
/// a demand to its entry's capacity, which it names).
pub const DEMAND_VPH: Range = Range {
    lo: 0.0,
    hi: 1e12,
    unit: "veh/h",
};

/// `mapc window --fit-floor`: a fraction of the source's length, above 0 and at most 1.
pub const FIT_FLOOR: Range = Range {
    lo: 0.001,
    hi: 1.0,
    unit: "",
};
/// `mapc window --n-av`: what a scenario's `control.n_av` may hold.
pub const WINDOW_N_AV: RangeInclusive<u64> = 0..=mapc_scenario::ranges::N_AV.hi as u64;

/// A count in `range`, as a `usize` or `u64` flag (clap names the flag and the range when it is outside).
pub fn count<T>(range: RangeInclusive<u64>) -> RangedU64ValueParser<T>
where
    T: TryFrom<u64> + Clone + Send + Sync + 'static,
    <T as TryFrom<u64>>::Error: std::fmt::Display + Send + Sync + 'static,
{
    RangedU64ValueParser::<T>::new().range(range)
}

/// `--seeds`: 1 to [`MAX_SEEDS`].
pub fn seeds() -> RangedU64ValueParser<u64> {
    count(1..=MAX_SEEDS)
}

/// `--first-seed`: 0 to [`MAX_FIRST_SEED`].
pub fn first_seed() -> RangedU64ValueParser<u64> {
    count(0..=MAX_FIRST_SEED)
}

/// `--threads`: 1 to [`MAX_THREADS`].
pub fn threads() -> RangedU64ValueParser<usize> {
    count(1..=MAX_THREADS)
}

/// `--width`, `--height`: 1 to [`MAX_PIXELS`].
pub fn pixels() -> RangedU64ValueParser<u32> {
    count(1..=MAX_PIXELS)
}

/// `--lane`: a lane index.
pub fn lane() -> RangedU64ValueParser<u8> {
    count(LANE_INDEX)
}

/// Numbers a flag may hold, compared with a [`Range`] as `f64`.
pub trait AsF64: FromStr + Clone + Send + Sync + 'static {
    fn as_f64(&self) -> f64;
}

impl AsF64 for f64 {
    fn as_f64(&self) -> f64 {
        *self
    }
}

impl AsF64 for f32 {
    fn as_f64(&self) -> f64 {
        *self as f64
    }
}

/// A number within `range` (finite: NaN and the infinities never are), parsed as the flag's own type.
pub fn within<T: AsF64>(range: Range) -> impl TypedValueParser<Value = T>
where
    <T as FromStr>::Err: std::fmt::Display,
{
    move |text: &str| -> Result<T, String> {
        let value: T = text
            .parse()
            .map_err(|e| format!("`{text}` is not a number ({e})"))?;
        if range.contains(value.as_f64()) {
            Ok(value)
        } else {
            Err(format!(
                "{} is outside the allowed range {}",
                show(value.as_f64()),
                range.describe()
            ))
        }
    }
}
