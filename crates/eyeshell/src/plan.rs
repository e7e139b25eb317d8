//! What a growth run writes, planned before it starts: the columns of its series and the
//! most bytes its files take together (the series' columns are the table of outputs'). A scene is checked against the plan (a run that
//! would write more is refused), and the run directory's writer follows it; neither
//! needs the other for that.

use crate::bvp::COLUMNS;
use crate::growth::{GROWTH_COLUMNS, PERIPHERAL_COLUMNS};
use crate::outputs::series_columns;

/// The most bytes one number takes in a run's CSV files (as the run directory formats it:
/// a sign, 17 digits, the point, `e-308`) with its separator.
pub const CELL_BYTES: u64 = 26;
/// The most bytes the files of one growth run may take together, as counted before it
/// starts ([`planned_bytes`]; `Scene` validation refuses more).
pub const MAX_RUN_BYTES: u64 = 8 << 30;

/// The most bytes a growth run writes: a snapshot of every node at t = 0 and at each of
/// `times` output times, the series, history and peripheral rows (summary.json and the marker
/// are small beside them). `images` is how many images the lenses worn form (0 without
/// lenses): peripheral.csv then holds a block of rows for each besides the naked eye's, and
/// the columns that say which.
pub fn planned_bytes(nodes: usize, times: usize, history_points: usize, images: usize) -> u64 {
    let row = |cells: usize| cells as u64 * CELL_BYTES;
    let snapshot = (nodes as u64 + 1) * row(COLUMNS.len() + GROWTH_COLUMNS.len() + 1);
    let series_rows = times as u64 + 2;
    let history_rows = (history_points + times) as u64 + 2;
    // Every file with room for the age column of a scene with time.unit; peripheral.csv: a row per
    // field angle, every 5° to at most 90°, per output time.
    let peripheral_rows = series_rows * 20 * (1 + images as u64);
    let peripheral_cells = PERIPHERAL_COLUMNS.len() + 1 + if images > 0 { 4 } else { 0 };
    (times as u64 + 1)
        .saturating_mul(snapshot)
        .saturating_add((series_rows + history_rows) * row(series_columns().len() + 1))
        .saturating_add(peripheral_rows * row(peripheral_cells))
}
