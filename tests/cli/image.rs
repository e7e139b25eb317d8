//! Figures written by the command line: eyeshell-plot draws to bytes and `eyeshell_cli::image`
//! writes them through the library's atomic writer.

use std::fs;

use eyeshell_cli::image::{self, ImageError};
use eyeshell_plot::{Figure, Series, SeriesStyle};

fn figure() -> Figure {
    Figure::new("f", "x", "y").with(Series::new(
        "a",
        vec![(0.0, 1.0), (1.0, 2.0)],
        SeriesStyle::Line,
    ))
}

#[test]
fn a_figure_is_written_as_the_bytes_it_renders_to() {
    let dir = tempfile::tempdir().unwrap();
    let (png, svg) = image::write(&figure(), &dir.path().join("sub/f.v1")).unwrap();
    assert_eq!(png, dir.path().join("sub/f.v1.png"));
    let drawn = eyeshell_plot::render(&figure()).unwrap();
    assert_eq!(fs::read(&png).unwrap(), drawn.png);
    assert_eq!(fs::read_to_string(&svg).unwrap(), drawn.svg);
    assert!(drawn.png.starts_with(b"\x89PNG") && drawn.svg.contains("<svg"));
    // Only the two files: no temporaries left beside them.
    let mut names: Vec<String> = fs::read_dir(dir.path().join("sub"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["f.v1.png", "f.v1.svg"]);
}

#[test]
fn errors_name_the_file_and_leave_what_is_there() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    fs::write(&file, "x").unwrap();
    let err = image::write(&figure(), &file.join("fig")).unwrap_err();
    assert!(matches!(err, ImageError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("a-file"), "{err}");
    assert_eq!(fs::read_to_string(&file).unwrap(), "x");
    // A figure that cannot be drawn writes nothing and names the stem.
    let tiny = Figure {
        width: 0,
        ..figure()
    };
    let err = image::write(&tiny, &dir.path().join("tiny")).unwrap_err();
    assert!(matches!(err, ImageError::Draw { .. }), "{err:?}");
    assert!(err.to_string().contains("tiny: figure size 0x650"), "{err}");
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
}
