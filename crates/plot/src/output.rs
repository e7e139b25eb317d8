//! Figures to bytes: the checks before drawing, the canvas of one figure or a grid of
//! panels, and the PNG and SVG drawn in memory. Writing them is the caller's.

#[allow(unused_imports)]
use crate::*;

/// One image, drawn twice: as PNG and as SVG.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    pub png: Vec<u8>,
    pub svg: String,
}

/// Draw the figure as PNG and SVG.
///
/// Points with a non-finite coordinate, or a non-positive one on a log axis, are dropped;
/// a series left empty is still in the legend, as "NAME (no data)". The axis ranges cover
/// every point with a margin (log axes: whole decades, and at least a factor 10^0.1 beyond
/// the data), unless the figure sets them. Errors come back as [`PlotError`].
pub fn render(fig: &Figure) -> Result<Image, PlotError> {
    check_size("figure", fig.width as u64, fig.height as u64)?;
    check_figure(fig, "")?;
    let canvas = Canvas {
        size: (fig.width, fig.height),
        title: "",
        cells: vec![Cell::new(fig, (0, 0), (fig.width, fig.height))],
    };
    draw_image(&canvas)
}

/// Height in pixels of the band holding the overall title of [`render_panels`] (none when
/// the title is empty).
pub const PANELS_TITLE_BAND: u32 = 50;

/// Draw several figures as the panels of one image.
///
/// The panels fill a grid row by row, `columns` to a row and `ceil(n / columns)` rows, each
/// drawn in a `panel_width`×`panel_height` cell exactly as [`render()`] would draw that figure
/// at that size (the figures' own `width` and `height` are not used). A non-empty `title`
/// goes in a band of [`PANELS_TITLE_BAND`] pixels on top, so the image is
/// `columns * panel_width` by `rows * panel_height` (+ the band) pixels. Unused cells of the
/// last row stay white. Errors, without writing anything, when there is no panel,
/// `columns` is 0, a panel or the whole image is outside 100..=20000 pixels a side, or a
/// figure is invalid for [`render()`]; otherwise as [`render()`].
pub fn render_panels(
    panels: &[Figure],
    columns: usize,
    title: &str,
    panel_width: u32,
    panel_height: u32,
) -> Result<Image, PlotError> {
    if panels.is_empty() {
        return Err(invalid("no panels to draw".to_string()));
    }
    if columns == 0 {
        return Err(invalid(
            "a grid of panels needs at least one column".to_string(),
        ));
    }
    check_size("panel", panel_width as u64, panel_height as u64)?;
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
    check_size("image", w, h)?;
    for (k, fig) in panels.iter().enumerate() {
        check_figure(fig, &format!("panel {}: ", k + 1))?;
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
    draw_image(&canvas)
}

pub(crate) fn invalid(reason: String) -> PlotError {
    PlotError::Invalid { reason }
}

/// Both sides within 100..=20000 pixels (plotters needs room for the axes; the PNG buffer
/// must fit in memory).
pub(crate) fn check_size(what: &str, w: u64, h: u64) -> Result<(), PlotError> {
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
    Err(invalid(format!(
        "{what} size {}x{} is outside 100..=20000 pixels",
        show(w),
        show(h)
    )))
}

pub(crate) fn check_figure(fig: &Figure, prefix: &str) -> Result<(), PlotError> {
    if fig.aspect_equal && (fig.x_scale != Scale::Linear || fig.y_scale != Scale::Linear) {
        return Err(invalid(format!(
            "{prefix}an equal aspect ratio needs both axes linear"
        )));
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

/// Draw the canvas as PNG and SVG in memory.
pub(crate) fn draw_image(canvas: &Canvas) -> Result<Image, PlotError> {
    ensure_font().map_err(|(tried, bad)| match bad {
        Some(font) => PlotError::BadFont { font },
        None => PlotError::NoFont { tried },
    })?;
    let (w, h) = canvas.size;
    let drawn = |message: String| PlotError::Draw { message };
    let rgb = draw_bitmap(canvas)?;
    let png = encode_png(&rgb, w, h).map_err(|e| drawn(format!("PNG encoding: {e}")))?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        draw_canvas(&root, canvas).map_err(drawn)?;
        root.present().map_err(|e| drawn(e.to_string()))?;
    }
    Ok(Image { png, svg })
}

/// The canvas drawn into an RGB buffer, row by row.
pub(crate) fn draw_bitmap(canvas: &Canvas) -> Result<Vec<u8>, PlotError> {
    let (w, h) = canvas.size;
    let drawn = |message: String| PlotError::Draw { message };
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw_canvas(&root, canvas).map_err(drawn)?;
        root.present().map_err(|e| drawn(e.to_string()))?;
    }
    Ok(rgb)
}

pub(crate) fn encode_png(rgb: &[u8], w: u32, h: u32) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    // Deflate level 1 (miniz_oxide's fast matcher) on rows filtered against the row
    // above: the paper's six figures encode in about 30 ms of CPU instead of about 200 ms
    // (the crate's default, level 6 with a filter chosen per row), for files 1.46 times
    // as large (926 KB against 635 KB in all). The charts are mostly flat colour, which
    // the Up filter turns into runs of zeros that even level 1 finds. fdeflate's fast mode
    // is faster still but makes files seven times as large with this filter.
    enc.set_deflate_compression(png::DeflateCompression::Level(1));
    enc.set_filter(png::Filter::Up);
    let mut writer = enc.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(png: &[u8]) -> (u32, u32, Vec<u8>) {
        let mut reader = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    /// The PNG holds exactly the pixels drawn, as the encoder's default settings did, and
    /// is at most 1.6 times as large.
    #[test]
    fn the_png_decodes_to_the_pixels_drawn() {
        let h: Vec<f64> = (0..40).map(|k| 0.1 + 0.05 * k as f64).collect();
        let fig = Figure::new("pixels", "x", "y")
            .with(Series::new(
                "sine",
                h.iter().map(|&x| (x, x.sin())).collect(),
                SeriesStyle::LineAndMarkers,
            ))
            .with(Series::new(
                "cosine",
                h.iter().map(|&x| (x, x.cos())).collect(),
                SeriesStyle::DashedLine,
            ));
        let canvas = Canvas {
            size: (fig.width, fig.height),
            title: "",
            cells: vec![Cell::new(&fig, (0, 0), (fig.width, fig.height))],
        };
        assert!(ensure_font().is_ok(), "no font to draw with");
        let rgb = draw_bitmap(&canvas).unwrap();
        let colours: std::collections::HashSet<&[u8]> = rgb.chunks(3).collect();
        assert!(colours.len() > 20, "{} colours", colours.len());
        let (w, h) = canvas.size;
        let png = encode_png(&rgb, w, h).unwrap();
        assert_eq!(decode(&png), (w, h, rgb.clone()));
        assert_eq!(render(&fig).unwrap().png, png);
        let mut before = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut before, w, h);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header().unwrap();
            writer.write_image_data(&rgb).unwrap();
            writer.finish().unwrap();
        }
        // Other bytes (the faster settings), the same pixels.
        assert_ne!(before, png);
        assert_eq!(decode(&before), decode(&png));
        assert!(
            png.len() * 10 <= before.len() * 16,
            "{} against {}",
            png.len(),
            before.len()
        );
    }
}
