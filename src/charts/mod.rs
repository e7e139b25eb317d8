//! The charts eyeshell draws from its results: the panels of the paper's result figures (its
//! section 3; docs/MODEL.md §8), `eyeshell plot`'s pictures of any run, the fit's and the
//! optics' charts; drawn from run directories read back from disk
//! ([`eyeshell::rundir::rundata`]), as PNG and SVG. "Figures" names only the paper's
//! figures (`eyeshell figures`, `study/figures.rs`, which runs their scenes).
//!
//! Panels are built by small functions (a shell cross-section, stretch profiles, axial
//! length against time, retinas); [`paper_figures`] composes them into figures (a)–(f) and
//! an HTML index, [`plot_run`] into the pictures of one run or of a sweep.

use std::path::PathBuf;

use crate::image::ImageError;
use eyeshell::interop::export::ExportError;
use eyeshell_plot::Rgb;

mod fit;
mod html;
mod optics;
mod panels;
mod paper;
mod plots;
mod population;
mod runs;

pub use fit::fit_figure;
pub use html::index_html;
pub use optics::{optics_figure, published_figure, RayFan};
pub use panels::{parameters, TimeAxis};
pub use paper::{paper_figure, paper_figures, PaperParts, PAPER_NEEDS, PAPER_STEMS};
pub use plots::{is_sweep, plot_compare, plot_run};
pub use population::{population_figure, POPULATION_FIGURE};
pub use runs::{read_fibre, read_grid, read_single, sweep_runs, PaperRuns};

/// Size of one panel, in pixels.
pub const PANEL: (u32, u32) = (820, 620);

const BLUE: Rgb = Rgb(31, 90, 220);
const RED: Rgb = Rgb(210, 40, 40);
const GREY: Rgb = Rgb(150, 150, 150);
const BLACK: Rgb = Rgb(0, 0, 0);

/// A figure that was written: its files and its caption (for the index).
#[derive(Clone, Debug)]
pub struct Written {
    pub id: String,
    pub title: String,
    pub caption: String,
    pub png: PathBuf,
    pub svg: PathBuf,
}

/// Why figures could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// A run that cannot be read back (the user's when it is missing or malformed).
    #[error(transparent)]
    Read(#[from] ExportError),
    /// Drawing or writing a picture failed (a missing font, a full disk): not the user's.
    #[error(transparent)]
    Plot(#[from] ImageError),
}

impl FigureError {
    /// Is it the user's (a run that is missing or malformed)?
    pub fn is_bad_input(&self) -> bool {
        matches!(self, FigureError::Read(e) if e.bad_input)
    }
}

impl From<FigureError> for eyeshell::Error {
    fn from(e: FigureError) -> Self {
        match e {
            FigureError::Read(e) => e.into(),
            FigureError::Plot(e) => eyeshell::Error::failed_by(eyeshell::Stage::Plot, e),
        }
    }
}
