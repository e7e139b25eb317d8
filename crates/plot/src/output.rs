//! Figures to files: the checks before drawing, the canvas of one figure or a grid of
//! panels, and the PNG and SVG written under temporary names and renamed into place.

#[allow(unused_imports)]
use crate::*;

/// `<stem><ext>`: the extension is appended, so dots in the stem stay.
pub(crate) fn with_suffix(stem: &Path, ext: &str) -> PathBuf {
    let mut s = OsString::from(stem.as_os_str());
    s.push(ext);
    PathBuf::from(s)
}

/// Write `<stem>.png` and `<stem>.svg`; returns the two paths.
///
/// Points with a non-finite coordinate, or a non-positive one on a log axis, are dropped;
/// a series left empty is still in the legend, as "NAME (no data)". The axis ranges cover
/// every point with a margin (log axes: whole decades, and at least a factor 10^0.1 beyond
/// the data), unless the figure sets them. Missing parent directories are created. Each
/// file is written under a temporary name in its directory and renamed into place, so no
/// half-written figure is left on error. Errors come back as [`PlotError`] naming the path.
pub fn write(fig: &Figure, stem: &Path) -> Result<(PathBuf, PathBuf), PlotError> {
    check_stem(stem)?;
    check_size(stem, "figure", fig.width as u64, fig.height as u64)?;
    check_figure(stem, fig, "")?;
    let canvas = Canvas {
        size: (fig.width, fig.height),
        title: "",
        cells: vec![Cell::new(fig, (0, 0), (fig.width, fig.height))],
    };
    render(&canvas, stem)
}

/// Height in pixels of the band holding the overall title of [`write_panels`] (none when
/// the title is empty).
pub const PANELS_TITLE_BAND: u32 = 50;

/// Write several figures as the panels of one image, `<stem>.png` and `<stem>.svg`.
///
/// The panels fill a grid row by row, `columns` to a row and `ceil(n / columns)` rows, each
/// drawn in a `panel_width`×`panel_height` cell exactly as [`write()`] would draw that figure
/// at that size (the figures' own `width` and `height` are not used). A non-empty `title`
/// goes in a band of [`PANELS_TITLE_BAND`] pixels on top, so the image is
/// `columns * panel_width` by `rows * panel_height` (+ the band) pixels. Unused cells of the
/// last row stay white. Errors, without writing anything, when there is no panel,
/// `columns` is 0, a panel or the whole image is outside 100..=20000 pixels a side, or a
/// figure is invalid for [`write()`]; otherwise as [`write()`].
pub fn write_panels(
    panels: &[Figure],
    columns: usize,
    title: &str,
    panel_width: u32,
    panel_height: u32,
    stem: &Path,
) -> Result<(PathBuf, PathBuf), PlotError> {
    check_stem(stem)?;
    if panels.is_empty() {
        return Err(invalid(stem, "no panels to draw".to_string()));
    }
    if columns == 0 {
        return Err(invalid(
            stem,
            "a grid of panels needs at least one column".to_string(),
        ));
    }
    check_size(stem, "panel", panel_width as u64, panel_height as u64)?;
    let rows = panels.len().div_ceil(columns);
    let band = if title.is_empty() {
        0
    } else {
        PANELS_TITLE_BAND
    };
    let total = |n: usize, px: u32, extra: u32| {
        (n as u64)
            .checked_mul(px as u64)
            .and_then(|v| v.checked_add(extra as u64))
            .unwrap_or(u64::MAX)
    };
    let (w, h) = (
        total(columns, panel_width, 0),
        total(rows, panel_height, band),
    );
    check_size(stem, "image", w, h)?;
    for (k, fig) in panels.iter().enumerate() {
        check_figure(stem, fig, &format!("panel {}: ", k + 1))?;
    }
    // Fits in i32: checked above to be at most 20000.
    let cells = panels
        .iter()
        .enumerate()
        .map(|(k, fig)| {
            let (r, c) = ((k / columns) as u32, (k % columns) as u32);
            let at = (c * panel_width, band + r * panel_height);
            Cell::new(fig, (at.0 as i32, at.1 as i32), (panel_width, panel_height))
        })
        .collect();
    let canvas = Canvas {
        size: (w as u32, h as u32),
        title,
        cells,
    };
    render(&canvas, stem)
}

pub(crate) fn invalid(stem: &Path, reason: String) -> PlotError {
    PlotError::Invalid {
        path: stem.to_path_buf(),
        reason,
    }
}

pub(crate) fn check_stem(stem: &Path) -> Result<(), PlotError> {
    match stem.file_name() {
        Some(_) => Ok(()),
        None => Err(invalid(
            stem,
            "the figure path has no file name".to_string(),
        )),
    }
}

/// Both sides within 100..=20000 pixels (plotters needs room for the axes; the PNG buffer
/// must fit in memory).
pub(crate) fn check_size(stem: &Path, what: &str, w: u64, h: u64) -> Result<(), PlotError> {
    let ok = |v: u64| (100..=20_000).contains(&v);
    if ok(w) && ok(h) {
        return Ok(());
    }
    let show = |v: u64| {
        if v == u64::MAX {
            "(too large)".to_string()
        } else {
            v.to_string()
        }
    };
    Err(invalid(
        stem,
        format!(
            "{what} size {}x{} is outside 100..=20000 pixels",
            show(w),
            show(h)
        ),
    ))
}

pub(crate) fn check_figure(stem: &Path, fig: &Figure, prefix: &str) -> Result<(), PlotError> {
    if fig.aspect_equal && (fig.x_scale != Scale::Linear || fig.y_scale != Scale::Linear) {
        return Err(invalid(
            stem,
            format!("{prefix}an equal aspect ratio needs both axes linear"),
        ));
    }
    Ok(())
}

/// One figure placed on a canvas: its top-left corner and its size, in pixels.
pub(crate) struct Cell<'a> {
    pub(crate) fig: std::borrow::Cow<'a, Figure>,
    pub(crate) prep: Prepared,
    pub(crate) at: (i32, i32),
    pub(crate) size: (u32, u32),
}

impl<'a> Cell<'a> {
    pub(crate) fn new(fig: &'a Figure, at: (i32, i32), size: (u32, u32)) -> Self {
        let fig = offset_axes(fig);
        let prep = Prepared::new(&fig);
        Cell {
            fig,
            prep,
            at,
            size,
        }
    }
}

/// Everything one image shows: its size, an overall title (may be empty) and the panels.
pub(crate) struct Canvas<'a> {
    pub(crate) size: (u32, u32),
    pub(crate) title: &'a str,
    pub(crate) cells: Vec<Cell<'a>>,
}

/// Draw the canvas as PNG and SVG in memory, then write both files atomically.
pub(crate) fn render(canvas: &Canvas, stem: &Path) -> Result<(PathBuf, PathBuf), PlotError> {
    let png_path = with_suffix(stem, ".png");
    let svg_path = with_suffix(stem, ".svg");
    ensure_font().map_err(|(tried, bad)| match bad {
        Some(font) => PlotError::BadFont {
            path: png_path.clone(),
            font,
        },
        None => PlotError::NoFont {
            path: png_path.clone(),
            tried,
        },
    })?;
    let (w, h) = canvas.size;
    let drawn = |path: &Path| {
        let path = path.to_path_buf();
        move |message: String| PlotError::Draw { path, message }
    };

    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw_canvas(&root, canvas).map_err(drawn(&png_path))?;
        root.present()
            .map_err(|e| drawn(&png_path)(e.to_string()))?;
    }
    let png_bytes = encode_png(&rgb, w, h).map_err(|e| PlotError::Io {
        path: png_path.clone(),
        source: e,
    })?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        draw_canvas(&root, canvas).map_err(drawn(&svg_path))?;
        root.present()
            .map_err(|e| drawn(&svg_path)(e.to_string()))?;
    }
    write_both(stem, (&png_path, &png_bytes), (&svg_path, svg.as_bytes()))?;
    Ok((png_path, svg_path))
}

/// Write the two files: both temporaries first, then both renames, so that an error
/// leaves neither half-written. Creates missing parent directories.
///
/// eyeshell's atomic writer is `eyeshell::rundir::atomic`; this crate depends on nothing of
/// eyeshell (the arrow is cli → plot), so it keeps this one small write of a figure's pair
/// of files, and its [`write()`] / [`write_panels`] keep taking a path.
pub(crate) fn write_both(
    stem: &Path,
    png: (&Path, &[u8]),
    svg: (&Path, &[u8]),
) -> Result<(), PlotError> {
    if let Some(parent) = stem.parent().filter(|p| !p.as_os_str().is_empty()) {
        fs::create_dir_all(parent).map_err(|e| PlotError::Io {
            path: parent.to_path_buf(),
            source: e,
        })?;
    }
    let png_tmp = write_temp(png.0, png.1)?;
    let svg_tmp = match write_temp(svg.0, svg.1) {
        Ok(t) => t,
        Err(e) => {
            let _ = fs::remove_file(&png_tmp);
            return Err(e);
        }
    };
    for (tmp, path) in [(&png_tmp, png.0), (&svg_tmp, svg.0)] {
        if let Err(e) = fs::rename(tmp, path) {
            let _ = fs::remove_file(&png_tmp);
            let _ = fs::remove_file(&svg_tmp);
            return Err(PlotError::Io {
                path: path.to_path_buf(),
                source: e,
            });
        }
    }
    Ok(())
}

pub(crate) fn encode_png(rgb: &[u8], w: u32, h: u32) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    // fdeflate's fast mode: encoding was most of a figure's drawing, and this halves the
    // CPU of drawing the paper's six figures, for files about twice as large (the
    // const shells: 96 KB with the default, 212 KB).
    enc.set_compression(png::Compression::Fast);
    let mut writer = enc.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()?;
    Ok(out)
}

/// Write `bytes` to a fresh hidden sibling of `path`; returns its name. Removed on error.
pub(crate) fn write_temp(path: &Path, bytes: &[u8]) -> Result<PathBuf, PlotError> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let tmp = path.with_file_name(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    if let Err(e) = fs::write(&tmp, bytes) {
        let _ = fs::remove_file(&tmp);
        return Err(PlotError::Io {
            path: path.to_path_buf(),
            source: e,
        });
    }
    Ok(tmp)
}
