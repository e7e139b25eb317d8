//! The font of the figures' text: found at run time and registered with plotters once.

#[allow(unused_imports)]
use crate::*;

/// Where the PNG font is looked for, in order (Debian first). `EYESHELL_PLOT_FONT`, when
/// set, names a TTF to try before these.
pub const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/local/share/fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
];

/// The environment variable naming a TTF font to use instead of [`FONT_PATHS`].
pub const FONT_ENV: &str = "EYESHELL_PLOT_FONT";

/// The font registered with plotters, once found (fonts are registered for the process).
pub(crate) static FONT: Mutex<Option<PathBuf>> = Mutex::new(None);

/// Find a TTF and register it as plotters' "sans-serif" (once per process). Returns its
/// path. A failure is not remembered, so installing the font later helps.
pub fn ensure_font() -> Result<PathBuf, (Vec<PathBuf>, Option<PathBuf>)> {
    let mut font = FONT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(path) = font.as_ref() {
        return Ok(path.clone());
    }
    let mut candidates: Vec<PathBuf> = Vec::new();
    if let Some(p) = std::env::var_os(FONT_ENV).filter(|p| !p.is_empty()) {
        candidates.push(PathBuf::from(p));
    }
    candidates.extend(FONT_PATHS.iter().map(PathBuf::from));
    for path in &candidates {
        let Ok(bytes) = std::fs::read(path) else {
            continue;
        };
        // plotters keeps the font for the life of the process: leak it once.
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_err() {
            return Err((candidates.clone(), Some(path.clone())));
        }
        *font = Some(path.clone());
        return Ok(path.clone());
    }
    Err((candidates, None))
}
