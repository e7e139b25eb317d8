//! Figures drawn by eyeshell-plot, written as `<stem>.png` and `<stem>.svg` through the
//! library's one atomic writer (`eyeshell::rundir::atomic`): eyeshell-plot draws to bytes
//! and writes no file.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use eyeshell::rundir::atomic::write_atomic;
use eyeshell_plot::{self as plot, Figure, PlotError};

/// Why a figure was not written. Display is one line naming the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{}: {source}", path.display())]
    Draw { path: PathBuf, source: PlotError },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// `<stem><ext>`: the extension is appended, so dots in the stem stay.
fn with_suffix(stem: &Path, ext: &str) -> PathBuf {
    let mut s = OsString::from(stem.as_os_str());
    s.push(ext);
    PathBuf::from(s)
}

/// Write the figure as `<stem>.png` and `<stem>.svg` (eyeshell-plot's `render`); returns the
/// two paths.
pub fn write(fig: &Figure, stem: &Path) -> Result<(PathBuf, PathBuf), ImageError> {
    let image = plot::render(fig);
    write_image(image, stem)
}

/// Write several figures as the panels of one image (eyeshell-plot's `render_panels`).
pub fn write_panels(
    panels: &[Figure],
    columns: usize,
    title: &str,
    panel_width: u32,
    panel_height: u32,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), ImageError> {
    let image = plot::render_panels(panels, columns, title, panel_width, panel_height);
    write_image(image, stem)
}

/// Write a drawn image: the PNG, then the SVG, each atomically (never half-written, on disk
/// when this returns), missing parent directories created. A drawing error names the stem
/// (nothing is written); a write error names the file.
fn write_image(
    image: Result<plot::Image, PlotError>,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), ImageError> {
    let image = image.map_err(|source| ImageError::Draw {
        path: stem.to_path_buf(),
        source,
    })?;
    if stem.file_name().is_none() {
        return Err(ImageError::Io {
            path: stem.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "the figure path has no file name",
            ),
        });
    }
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| ImageError::Io { path, source }
    };
    if let Some(parent) = stem.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(io(parent))?;
    }
    let png = with_suffix(stem, ".png");
    let svg = with_suffix(stem, ".svg");
    write_atomic(&png, &image.png).map_err(io(&png))?;
    write_atomic(&svg, image.svg.as_bytes()).map_err(io(&svg))?;
    Ok((png, svg))
}
