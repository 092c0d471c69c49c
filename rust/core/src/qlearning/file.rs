//! Q-table files: [`QTable::save`] and [`QTable::load`].
//!
//! # Format (version 1)
//!
//! ```text
//! SIXAXIS-QTABLE 1\n
//! {JSON header}\n
//! num_states * 6 values (f64 or f32, as `values` says), little-endian, row-major (state, action)
//! ```
//! The header records `num_states`, `actions` (6), `values` (`"f64"` or `"f32"`; a file
//! without it, written before f32 tables existed, holds f64), `bounds`, `start`, `target`,
//! `blocked_cells` (count), `fingerprint` (FNV-1a 64 of bounds, blocked cells and target,
//! hex), `values_checksum` (FNV-1a 64 of the value bytes, hex) and `layout` (the same in
//! words). Values are stored as raw bits, so a round trip is exact in either precision.
//! [`QTable::load`] returns the table in the file's precision ([`train`] converts it to the
//! run's). It answers [`Error::QTableMismatch`](crate::Error::QTableMismatch) when
//! bounds, target or blocked cells differ from the world's; a file that is not a Q-table,
//! is truncated or fails its checksum gives an [`Error::Io`](crate::Error::Io) of kind `InvalidData`.
//! Saving writes a temporary file in the same directory and renames it over the target;
//! on any error the temporary file is removed.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::table::{rows_of, with_rows, QTable, QValue, Rows};
use crate::error::{Error, Result};
use crate::grid::{Fnv, GridWorld, NUM_ACTIONS};
use crate::scenario::{Bounds, Cell, QPrecision};

impl QTable {
    /// Write the table to `path` atomically (temporary file in the same directory, then
    /// rename), with a header that ties it to `world` (see the module docs for the format).
    pub fn save(&self, path: &Path, world: &GridWorld) -> Result<()> {
        if self.num_states() != world.num_states() {
            return Err(Error::QTableMismatch(format!(
                "table has {} states, world has {}",
                self.num_states(),
                world.num_states()
            )));
        }
        let precision = self.precision();
        let mut body = Vec::with_capacity(self.num_states() * self.bytes_per_state());
        with_rows!(&self.rows, r => r.as_flattened().iter().for_each(|v| v.write_le(&mut body)));
        let mut ck = Fnv::new();
        ck.write(&body);
        let header = FileHeader {
            format: FORMAT_NAME.to_string(),
            version: FORMAT_VERSION,
            num_states: self.num_states(),
            actions: NUM_ACTIONS,
            values: Some(precision.name().to_string()),
            bounds: world.bounds(),
            start: world.cell_of(world.start()),
            target: world.cell_of(world.target()),
            blocked_cells: world.num_blocked(),
            fingerprint: format!("{:016x}", world.fingerprint()),
            values_checksum: format!("{:016x}", ck.finish()),
            layout: format!(
                "{} little-endian, row-major (state, action); actions +x -x +y -y +z -z",
                precision.name()
            ),
        };
        let mut bytes = format!("{MAGIC}\n").into_bytes();
        bytes.extend_from_slice(
            serde_json::to_string(&header)
                .expect("a header always serialises")
                .as_bytes(),
        );
        bytes.push(b'\n');
        bytes.extend_from_slice(&body);
        crate::io::write_atomic(path, &bytes)
    }

    /// Read a table written by [`QTable::save`] and check it fits `world`
    /// ([`Error::QTableMismatch`](crate::Error::QTableMismatch) if bounds, target or blocked cells differ).
    pub fn load(path: &Path, world: &GridWorld) -> Result<QTable> {
        // A table of `world` is its values (at most 8 bytes each, f64) plus a header of a
        // few hundred bytes: reading no more than that keeps `/dev/zero` or a huge stray
        // file from exhausting memory.
        let largest = QPrecision::F64.value_bytes();
        let max_bytes = (world.num_states() * NUM_ACTIONS * largest + MAX_HEADER_BYTES) as u64;
        let bytes = crate::io::read_bounded(path, max_bytes)?;
        QTable::from_file_bytes(&bytes, world, path)
    }

    /// Parse the bytes of a Q-table file (as [`QTable::save`] writes them) and check they
    /// fit `world`; `path` only names the source in errors. Every malformed input (truncated,
    /// bit-flipped, another world's) is an error, never a panic.
    pub fn from_file_bytes(bytes: &[u8], world: &GridWorld, path: &Path) -> Result<QTable> {
        let bad = |why: String| {
            Error::io(
                path,
                std::io::Error::new(std::io::ErrorKind::InvalidData, why),
            )
        };
        let magic = format!("{MAGIC}\n");
        if !bytes.starts_with(magic.as_bytes()) {
            return Err(bad(format!(
                "not a SixAxisAvoid Q-table file (expected first line `{MAGIC}`)"
            )));
        }
        let rest = &bytes[magic.len()..];
        let nl = rest
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| bad("Q-table header is not terminated".to_string()))?;
        let header: FileHeader = serde_json::from_slice(&rest[..nl])
            .map_err(|e| bad(format!("Q-table header is invalid: {e}")))?;
        if header.format != FORMAT_NAME || header.version != FORMAT_VERSION {
            return Err(bad(format!(
                "unsupported Q-table format {} version {}",
                header.format, header.version
            )));
        }
        // Files written before f32 tables existed have no `values` field: f64.
        let precision = match header.values.as_deref() {
            None => QPrecision::F64,
            Some(name) => QPrecision::from_name("values", name)
                .map_err(|_| bad(format!("Q-table header has an unknown value type: {name}")))?,
        };
        if header.actions != NUM_ACTIONS {
            return Err(Error::QTableMismatch(format!(
                "file has {} actions per state, expected {NUM_ACTIONS}",
                header.actions
            )));
        }
        let wb = world.bounds();
        if header.bounds != wb || header.num_states != world.num_states() {
            return Err(Error::QTableMismatch(format!(
                "bounds differ: file min {:?} max {:?} ({} states), world min {:?} max {:?} ({} states)",
                header.bounds.min,
                header.bounds.max,
                header.num_states,
                wb.min,
                wb.max,
                world.num_states()
            )));
        }
        let wt = world.cell_of(world.target());
        if header.target != wt {
            return Err(Error::QTableMismatch(format!(
                "target differs: file {:?}, world {:?}",
                header.target, wt
            )));
        }
        let wf = format!("{:016x}", world.fingerprint());
        if header.fingerprint != wf {
            return Err(Error::QTableMismatch(format!(
                "obstacles differ: file has {} blocked cells (fingerprint {}), world has {} (fingerprint {wf})",
                header.blocked_cells,
                header.fingerprint,
                world.num_blocked()
            )));
        }
        let body = &rest[nl + 1..];
        let expected = header.num_states * NUM_ACTIONS * precision.value_bytes();
        if body.len() != expected {
            return Err(bad(format!(
                "Q-table values have {} bytes, expected {expected} ({} {} values)",
                body.len(),
                header.num_states * NUM_ACTIONS,
                precision.name()
            )));
        }
        let mut ck = Fnv::new();
        ck.write(body);
        if format!("{:016x}", ck.finish()) != header.values_checksum {
            return Err(bad("Q-table values fail their checksum".to_string()));
        }
        let rows = match precision {
            QPrecision::F64 => parse_rows::<f64>(header.num_states, body),
            QPrecision::F32 => parse_rows::<f32>(header.num_states, body),
        };
        rows.map(|rows| QTable { rows }).map_err(|(i, v)| {
            bad(format!(
                "Q-table value {i} (state {}, action {}) is {v}, not a finite number",
                i / NUM_ACTIONS,
                i % NUM_ACTIONS,
            ))
        })
    }
}

/// The rows of a file's value bytes (`num_states * 6 * V::BYTES` of them, checked), or the
/// index and value of the first value that is not finite.
fn parse_rows<V: QValue>(
    num_states: usize,
    body: &[u8],
) -> std::result::Result<Rows, (usize, f64)> {
    let values: Vec<V> = body
        .chunks_exact(V::PRECISION.value_bytes())
        .map(V::read_le)
        .collect();
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err((i, values[i].to_f64()));
    }
    Ok(V::wrap(
        rows_of(num_states, &values).expect("the body length was checked"),
    ))
}

const MAGIC: &str = "SIXAXIS-QTABLE 1";
/// Bound on a Q-table file's magic line and JSON header, bytes.
const MAX_HEADER_BYTES: usize = 64 * 1024;
const FORMAT_NAME: &str = "sixaxis-qtable";
const FORMAT_VERSION: u32 = 1;

#[derive(Debug, Serialize, Deserialize)]
struct FileHeader {
    format: String,
    version: u32,
    num_states: usize,
    actions: usize,
    /// `"f64"` or `"f32"`; absent (f64) in files written before f32 tables existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    values: Option<String>,
    bounds: Bounds,
    start: Cell,
    target: Cell,
    blocked_cells: usize,
    fingerprint: String,
    values_checksum: String,
    layout: String,
}
