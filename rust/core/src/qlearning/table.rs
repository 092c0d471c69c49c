//! The Q-table: `num_states` rows of six actions, stored as f64 (the default) or f32
//! ([`QPrecision`](crate::scenario::QPrecision)); every accessor reads and writes the values as f64.
//!
//! Entry points: [`QTable::zeros_with`], [`QTable::from_values`] /
//! [`QTable::from_values_f32`], [`QTable::get`] / [`QTable::set`], [`QTable::into_precision`].

use crate::error::{Error, Result};
use crate::grid::NUM_ACTIONS;
use crate::scenario::QPrecision;

/// Q-values: `num_states` rows of six actions, stored as f64 (the default) or f32
/// ([`QPrecision`](crate::scenario::QPrecision)); every accessor reads and writes them as f64.
#[derive(Debug, Clone, PartialEq)]
pub struct QTable {
    pub(super) rows: Rows,
}

/// The rows of a [`QTable`], in its precision.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Rows {
    F64(Vec<[f64; NUM_ACTIONS]>),
    F32(Vec<[f32; NUM_ACTIONS]>),
}

/// `body` with `$r` bound to the rows of `$rows`, whatever their value type.
macro_rules! with_rows {
    ($rows:expr, $r:ident => $body:expr) => {
        match $rows {
            Rows::F64($r) => $body,
            Rows::F32($r) => $body,
        }
    };
}
pub(super) use with_rows;

/// A type Q-values are stored in. Arithmetic is always done in f64: a value is read with
/// [`QValue::to_f64`] and an update's result stored with [`QValue::from_f64`] (the identity
/// for f64, rounding to nearest for f32).
pub(super) trait QValue: Copy + PartialOrd + std::fmt::Debug {
    const PRECISION: QPrecision;
    const ZERO: Self;
    fn from_f64(v: f64) -> Self;
    fn to_f64(self) -> f64;
    fn is_finite(self) -> bool;
    /// Append the little-endian bytes.
    fn write_le(self, out: &mut Vec<u8>);
    /// From `PRECISION.value_bytes()` little-endian bytes.
    fn read_le(bytes: &[u8]) -> Self;
    fn wrap(rows: Vec<[Self; NUM_ACTIONS]>) -> Rows;
}

/// [`QValue`] for a float type `$t` stored as `Rows::$variant`.
macro_rules! impl_q_value {
    ($t:ty, $variant:ident) => {
        impl QValue for $t {
            const PRECISION: QPrecision = QPrecision::$variant;
            const ZERO: Self = 0.0;
            #[inline(always)]
            fn from_f64(v: f64) -> Self {
                // The identity for f64; rounding to nearest for f32.
                v as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            fn write_le(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            fn read_le(bytes: &[u8]) -> Self {
                <$t>::from_le_bytes(bytes.try_into().expect("one value's bytes"))
            }
            fn wrap(rows: Vec<[Self; NUM_ACTIONS]>) -> Rows {
                Rows::$variant(rows)
            }
        }
    };
}

impl_q_value!(f64, F64);
impl_q_value!(f32, F32);

/// Rows of six from flat row-major values (`num_states * 6` of them).
pub(super) fn rows_of<V: QValue>(num_states: usize, values: &[V]) -> Result<Vec<[V; NUM_ACTIONS]>> {
    if values.len() != num_states * NUM_ACTIONS {
        return Err(Error::argument(
            "values",
            format!("{} values", values.len()),
            format!("expected num_states * 6 = {}", num_states * NUM_ACTIONS),
        ));
    }
    Ok(values
        .chunks_exact(NUM_ACTIONS)
        .map(|c| c.try_into().expect("chunks of six"))
        .collect())
}

/// Index of the largest value, lowest index on ties.
#[inline(always)]
pub(super) fn argmax_lowest<V: QValue>(row: &[V; NUM_ACTIONS]) -> usize {
    max_mask(row).trailing_zeros() as usize
}

/// Bit `a` set for every action of maximal value (branch-free).
#[inline(always)]
pub(super) fn max_mask<V: QValue>(row: &[V; NUM_ACTIONS]) -> u32 {
    mask_of(row, row_max(row))
}

/// Bit `a` set for every action whose value equals `m`.
#[inline(always)]
pub(super) fn mask_of<V: QValue>(row: &[V; NUM_ACTIONS], m: V) -> u32 {
    let mut mask = 0u32;
    for (i, &v) in row.iter().enumerate() {
        mask |= ((v == m) as u32) << i;
    }
    mask
}

/// Index of the `n`-th set bit (from 0, lowest first) of `mask`.
#[inline]
pub(super) fn nth_set_bit(mut mask: u32, n: u32) -> usize {
    for _ in 0..n {
        mask &= mask - 1;
    }
    mask.trailing_zeros() as usize
}

#[inline(always)]
pub(super) fn row_max<V: QValue>(row: &[V; NUM_ACTIONS]) -> V {
    // A tree (depth 3, not a chain of 5): the value is the same, the latency shorter.
    let a = if row[1] > row[0] { row[1] } else { row[0] };
    let b = if row[3] > row[2] { row[3] } else { row[2] };
    let c = if row[5] > row[4] { row[5] } else { row[4] };
    let ab = if b > a { b } else { a };
    if c > ab {
        c
    } else {
        ab
    }
}

/// Eq. 6: `old + alpha * (reward + gamma * bootstrap - old)`.
#[inline(always)]
pub(super) fn updated(old: f64, reward: f64, bootstrap: f64, alpha: f64, gamma: f64) -> f64 {
    old + alpha * (reward + gamma * bootstrap - old)
}

/// The rows of `values`, converted to `V`; an error names the first value that does not
/// fit `V` (finite f64s beyond the f32 range become infinite).
pub(super) fn converted<V: QValue, W: QValue>(
    values: &[[W; NUM_ACTIONS]],
) -> Result<Vec<[V; NUM_ACTIONS]>> {
    let rows: Vec<[V; NUM_ACTIONS]> = values
        .iter()
        .map(|row| row.map(|v| V::from_f64(v.to_f64())))
        .collect();
    for (s, row) in rows.iter().enumerate() {
        if let Some(a) = row.iter().position(|v| !v.is_finite()) {
            return Err(Error::argument(
                "q_precision",
                V::PRECISION.name(),
                format!(
                    "Q-value {} (state {s}, action {a}) does not fit in {}",
                    values[s][a].to_f64(),
                    V::PRECISION.name()
                ),
            ));
        }
    }
    Ok(rows)
}

impl QTable {
    /// All zeros, f64.
    pub fn zeros(num_states: usize) -> Self {
        QTable::zeros_with(num_states, QPrecision::F64)
    }

    /// All zeros, in `precision`.
    pub fn zeros_with(num_states: usize, precision: QPrecision) -> Self {
        let rows = match precision {
            QPrecision::F64 => Rows::F64(vec![[0.0; NUM_ACTIONS]; num_states]),
            QPrecision::F32 => Rows::F32(vec![[0.0; NUM_ACTIONS]; num_states]),
        };
        QTable { rows }
    }

    /// An f64 table from flat row-major values (`num_states * 6` of them).
    pub fn from_values(num_states: usize, values: Vec<f64>) -> Result<Self> {
        Ok(QTable {
            rows: Rows::F64(rows_of(num_states, &values)?),
        })
    }

    /// An f32 table from flat row-major values (`num_states * 6` of them).
    pub fn from_values_f32(num_states: usize, values: Vec<f32>) -> Result<Self> {
        Ok(QTable {
            rows: Rows::F32(rows_of(num_states, &values)?),
        })
    }

    /// The same values in `precision`: exact from f32 to f64, rounded to the nearest f32
    /// the other way (an error names a value beyond the f32 range). A no-op if the table
    /// already has that precision.
    pub fn into_precision(self, precision: QPrecision) -> Result<Self> {
        let rows = match (self.rows, precision) {
            (Rows::F64(r), QPrecision::F32) => Rows::F32(converted(&r)?),
            (Rows::F32(r), QPrecision::F64) => Rows::F64(converted(&r)?),
            (rows, _) => rows,
        };
        Ok(QTable { rows })
    }

    /// The type the values are stored in.
    pub fn precision(&self) -> QPrecision {
        match self.rows {
            Rows::F64(_) => QPrecision::F64,
            Rows::F32(_) => QPrecision::F32,
        }
    }

    /// Bytes of Q-values per state: 48 for f64, 24 for f32.
    pub fn bytes_per_state(&self) -> usize {
        NUM_ACTIONS * self.precision().value_bytes()
    }

    /// Number of states.
    pub fn num_states(&self) -> usize {
        with_rows!(&self.rows, r => r.len())
    }

    /// All values as f64 (exact for both precisions), row-major (state, action); a copy.
    pub fn values(&self) -> Vec<f64> {
        with_rows!(&self.rows, r => r.as_flattened().iter().map(|v| v.to_f64()).collect())
    }

    /// The values of an f64 table, row-major, without a copy (`None` for f32).
    pub fn values_f64(&self) -> Option<&[f64]> {
        match &self.rows {
            Rows::F64(r) => Some(r.as_flattened()),
            Rows::F32(_) => None,
        }
    }

    /// The values of an f32 table, row-major, without a copy (`None` for f64).
    pub fn values_f32(&self) -> Option<&[f32]> {
        match &self.rows {
            Rows::F32(r) => Some(r.as_flattened()),
            Rows::F64(_) => None,
        }
    }

    /// Q(s, a).
    #[inline]
    pub fn get(&self, s: usize, a: usize) -> f64 {
        with_rows!(&self.rows, r => r[s][a].to_f64())
    }

    /// Set Q(s, a) (rounded to the nearest f32 in an f32 table).
    #[inline]
    pub fn set(&mut self, s: usize, a: usize, value: f64) {
        with_rows!(&mut self.rows, r => r[s][a] = QValue::from_f64(value))
    }

    /// The six values of a state.
    #[inline]
    pub fn row(&self, s: usize) -> [f64; NUM_ACTIONS] {
        with_rows!(&self.rows, r => r[s].map(QValue::to_f64))
    }

    /// `max_a Q(s, a)`.
    #[inline]
    pub fn max_value(&self, s: usize) -> f64 {
        with_rows!(&self.rows, r => row_max(&r[s]).to_f64())
    }

    /// The greedy action of a state, ties broken by the lowest action index.
    #[inline]
    pub fn greedy_action(&self, s: usize) -> usize {
        with_rows!(&self.rows, r => argmax_lowest(&r[s]))
    }
}
