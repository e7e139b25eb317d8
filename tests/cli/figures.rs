//! `eyeshell figures` and `eyeshell plot`: every figure is a valid, non-trivial PNG and SVG;
//! what they show is read from the runs (change the data and the figure changes); and the
//! runs behind them agree with the paper's own account of its results (its section 3).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::support::*;
use eyeshell::rundir::rundata::{self, RunData};
use eyeshell_cli::charts::sweep_runs;

use eyeshell_cli::charts::PAPER_STEMS as FIGURES;

/// `eyeshell figures` once for the whole file (twelve growth runs, eleven of them solved).
fn figures() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap().keep().join("figures");
        let run = ok(&["figures", "--out", s(&dir)]);
        for f in FIGURES {
            assert!(run.stdout.contains(&format!("{f}.png")), "{}", run.stdout);
        }
        dir
    })
}

/// Decode a PNG: (width, height, number of distinct colours).
fn png_stats(path: &Path) -> (u32, u32, usize) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = info.color_type.samples();
    let colours: std::collections::HashSet<&[u8]> = buf[..info.buffer_size()].chunks(px).collect();
    (info.width, info.height, colours.len())
}

#[test]
fn every_figure_is_a_valid_non_trivial_png_and_svg() {
    let dir = figures();
    for f in FIGURES {
        let png = dir.join(format!("{f}.png"));
        let (w, h, colours) = png_stats(&png);
        assert!(w >= 1000 && h >= 600, "{f}: {w}x{h}");
        assert!(colours > 50, "{f}: only {colours} colours");
        assert!(
            std::fs::metadata(&png).unwrap().len() > 30_000,
            "{f}.png is small"
        );
        let svg = std::fs::read_to_string(dir.join(format!("{f}.svg"))).unwrap();
        assert!(
            svg.trim_start().starts_with("<svg") || svg.trim_start().starts_with("<?xml"),
            "{f}.svg"
        );
        assert!(svg.trim_end().ends_with("</svg>"), "{f}.svg is cut short");
        let curves = svg.matches("<polyline").count()
            + svg.matches("<path").count()
            + svg.matches("<line").count();
        assert!(curves > 20, "{f}.svg: {curves} curves");
        assert!(svg.len() > 20_000, "{f}.svg is small");
    }
    // The shells are shaded by η: a colour bar labelled η.
    let a = std::fs::read_to_string(dir.join("fig_a_const_shells.svg")).unwrap();
    assert!(a.contains("η (1/mm)"));
    // The index lists every figure with a caption that states the parameters.
    let index = std::fs::read_to_string(dir.join("index.html")).unwrap();
    for f in FIGURES {
        assert!(
            index.contains(&format!("src=\"{f}.png\"")),
            "{f} not in index.html"
        );
        assert!(
            index.contains(&format!("href=\"{f}.svg\"")),
            "{f}.svg not linked"
        );
    }
    for p in [
        "C = 100 kPa",
        "D = 100 kPa",
        "E_b = 18 kPa·mm³",
        "η0 = 70 /mm",
        "Γ = 8 mm",
        "δ = 4 mm",
        "uniform H = 0.65 mm",
        "non-uniform H(Σ)",
        "501 nodes",
    ] {
        assert!(index.contains(p), "{p} not in index.html");
    }
}

/// scenes/thick.toml is the fibre sweep's D = 0 run: solved once, and the twin's directory
/// holds the same data files byte for byte under its own scene.toml and summary.json; the
/// figures' summary.json says 11 runs were solved and 1 shared.
#[test]
fn the_thick_run_is_solved_once_and_shared_with_fibre_d0() {
    let dir = figures();
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["runs_solved"], 11);
    assert_eq!(summary["runs_shared"], 1);
    let (thick, d0) = (
        dir.join("data/thick/runs/run"),
        dir.join("data/fibre/runs/D=0"),
    );
    let files = |run: &Path| {
        let mut v: Vec<_> = walk(run)
            .into_iter()
            .map(|p| p.strip_prefix(run).unwrap().to_path_buf())
            .collect();
        v.sort();
        v
    };
    let names = files(&thick);
    assert_eq!(names, files(&d0));
    for data in ["series.csv", "history.csv", "peripheral.csv"] {
        assert!(names.contains(&PathBuf::from(data)), "{data}: {names:?}");
    }
    assert_eq!(
        names.iter().filter(|p| p.starts_with("snapshots")).count(),
        5
    );
    for name in &names {
        let (a, b) = (
            std::fs::read(thick.join(name)).unwrap(),
            std::fs::read(d0.join(name)).unwrap(),
        );
        let own = ["scene.toml", "summary.json", "result.json"]
            .iter()
            .any(|o| name == Path::new(o));
        assert_eq!(a == b, !own, "{}", name.display());
    }
    let toml = |run: &Path| std::fs::read_to_string(run.join("scene.toml")).unwrap();
    assert!(
        toml(&thick).starts_with("name = \"thick/run\"\ndescription = \"The paper's thick scene")
    );
    assert!(toml(&d0).starts_with("name = \"fibre/D=0\"\ndescription = \"The paper's fibre scenes"));
    let scene = |run: &Path| {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap())
                .unwrap();
        v["scene"].clone()
    };
    assert_eq!(scene(&thick)["name"], "thick/run");
    assert_eq!(scene(&thick)["path"], "scenes/thick.toml");
    assert_eq!(scene(&d0)["name"], "fibre/D=0");
    assert_eq!(scene(&d0)["path"], "scenes/fibre.toml");
}

/// Every regular file below `dir` (the marker and hidden names included).
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// The numbers written as text in an SVG (tick labels among them).
fn svg_numbers(svg: &str) -> Vec<f64> {
    svg.split('>')
        .filter_map(|chunk| chunk.split('<').next())
        .filter_map(|t| t.trim().parse::<f64>().ok())
        .collect()
}

#[test]
fn the_figures_show_what_the_runs_wrote() {
    // Copy the figures and their data, shift every axial length of the grid runs by +7 mm,
    // and draw again from the data alone.
    let src = figures();
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("figures");
    copy_dir(src, &copy);
    let before = std::fs::read_to_string(copy.join("fig_f_axial.svg")).unwrap();
    let ticks = svg_numbers(&before);
    assert!(
        ticks.iter().any(|&v| (19.0..=25.0).contains(&v)),
        "{ticks:?}"
    );
    for run in std::fs::read_dir(copy.join("data/grow/runs")).unwrap() {
        let history = run.unwrap().path().join("history.csv");
        let text = std::fs::read_to_string(&history).unwrap();
        let shifted: Vec<String> = text
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i == 0 {
                    return l.to_string();
                }
                let mut cells: Vec<String> = l.split(',').map(String::from).collect();
                cells[1] = format!("{}", cells[1].parse::<f64>().unwrap() + 7.0);
                cells.join(",")
            })
            .collect();
        std::fs::write(&history, shifted.join("\n") + "\n").unwrap();
    }
    ok(&["figures", "--replot", "--out", s(&copy), "--quiet"]);
    let after = std::fs::read_to_string(copy.join("fig_f_axial.svg")).unwrap();
    assert_ne!(before, after);
    let ticks = svg_numbers(&after);
    assert!(
        ticks.iter().any(|&v| (26.0..=32.0).contains(&v)),
        "the shifted lengths are not on the axis: {ticks:?}"
    );
    assert!(
        !ticks.iter().any(|&v| (19.0..=25.0).contains(&v)),
        "old lengths still on the axis: {ticks:?}"
    );
    // The captions are read from the data too.
    let index = std::fs::read_to_string(copy.join("index.html")).unwrap();
    let old = std::fs::read_to_string(src.join("index.html")).unwrap();
    assert_ne!(index, old);
    // The figures that do not use the grid are drawn the same.
    assert_eq!(
        std::fs::read(copy.join("fig_d_fibre.png")).unwrap(),
        std::fs::read(src.join("fig_d_fibre.png")).unwrap()
    );
    // --replot without data is bad input.
    let empty = dir.path().join("nothing");
    assert_bad(
        &eyeshell(&["figures", "--replot", "--out", s(&empty)]),
        "no data to replot",
        "replot",
    );
}

/// A file cut short: its new text, and what the error says of it.
type Cut = fn(&str) -> (String, String);

/// `figures --replot` names the snapshot that was cut short, and the line, whether the cut
/// falls inside a line or at a line end, in a single run or in a sweep's run (a sweep
/// that fails to read is not read again as a plain run, which would blame the sweep's own
/// directory).
#[test]
fn replot_names_the_snapshot_cut_short() {
    let src = figures();
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("figures");
    let snapshot = "snapshots/snapshot_00002_t0.200000.csv";
    for run in ["const/runs/run", "thick/runs/run", "fibre/runs/D=200"] {
        let file = copy.join("data").join(run).join(snapshot);
        // Bytes cut as `truncate -s` would, inside line L; and whole lines, at a line end.
        let cuts: [Cut; 2] = [
            |t| {
                let cut = &t[..t.len() / 2];
                let line = cut.matches('\n').count() + 1;
                (cut.to_string(), format!("line {line}: "))
            },
            |t| {
                let cut = t.lines().take(11).map(|l| format!("{l}\n")).collect();
                (cut, "line 11: the file ends after 10 rows".to_string())
            },
        ];
        for cut in cuts {
            let _ = std::fs::remove_dir_all(&copy);
            copy_dir(src, &copy);
            let (text, needle) = cut(&std::fs::read_to_string(&file).unwrap());
            std::fs::write(&file, text).unwrap();
            let r = eyeshell(&["figures", "--replot", "--out", s(&copy)]);
            let needle = format!("{}: {needle}", file.display());
            assert_bad(&r, &needle, run);
        }
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

// ---------------------------------------------------------------- the paper's account

fn data(name: &str) -> Vec<RunData> {
    sweep_runs(&figures().join("data").join(name)).unwrap()
}

fn final_length(r: &RunData) -> f64 {
    r.timeline().last().unwrap().axial_length
}

fn length_at(r: &RunData, t: f64) -> f64 {
    r.timeline()
        .iter()
        .find(|p| (p.t - t).abs() < 1e-9)
        .unwrap()
        .axial_length
}

fn col(r: &RunData, t: f64, name: &str) -> Vec<f64> {
    r.snapshot_near(t).unwrap().table.column(name).unwrap()
}

/// "The const eye grows past the blue surface, while the fastest growth moves towards the
/// equator."
#[test]
fn const_grows_past_blue_and_its_fastest_growth_moves_to_the_equator() {
    let run = &data("const")[0];
    let end = run.timeline().last().unwrap();
    assert!(end.retina_minus_blue > 0.3, "{end:?}");
    let mut peaks = Vec::new();
    for t in [0.1, 0.2, 0.4, 1.0] {
        let (sigma, eta) = (col(run, t, "Sigma"), col(run, t, "eta"));
        let k = (0..eta.len())
            .max_by(|&a, &b| eta[a].total_cmp(&eta[b]))
            .unwrap();
        peaks.push(sigma[k]);
    }
    assert!(peaks.windows(2).all(|w| w[1] > w[0] + 0.5), "{peaks:?}");
    assert!(peaks[3] > 9.0 && peaks[3] < 15.7, "{peaks:?}");
}

/// "The retina is marginally shifted forwards [with the non-uniform thickness] ... the
/// non-uniform reference configuration serves to reduce both stretches near the posterior."
#[test]
fn the_non_uniform_shell_is_marginally_shorter_with_smaller_posterior_stretches() {
    let (thick, uniform) = (&data("thick")[0], &data("const")[0]);
    let (lt, lu) = (final_length(thick), final_length(uniform));
    assert!(lt < lu && lu - lt < 0.5, "{lt} {lu}");
    for field in ["alpha_s", "alpha_phi"] {
        let (a, b) = (col(thick, 1.0, field)[0], col(uniform, 1.0, field)[0]);
        assert!(a < b - 1e-3, "{field} at the pole: {a} against {b}");
    }
}

/// "Whilst the most reinforced shell has the greatest final length, the shell with only
/// slight reinforcement exhibits a reduced length compared to the fibre-free shell", "a
/// lower rate of growth over an extended period".
#[test]
fn the_effect_of_fibres_on_axial_length_is_not_monotone() {
    let runs = data("fibre");
    let by_d = |d: f64| runs.iter().find(|r| r.scene.params.d == d).unwrap();
    let l = |d: f64| final_length(by_d(d));
    assert!(l(100.0) < l(0.0), "{} {}", l(100.0), l(0.0));
    assert!(l(400.0) > l(0.0) && l(400.0) > l(100.0) && l(400.0) > l(200.0));
    assert!(length_at(by_d(400.0), 0.1) < length_at(by_d(0.0), 0.1));
}

/// "δ = 6 gives near-spherical retinas and an axial length nearly independent of Γ";
/// "increasing Γ is associated with rapid initial growth"; the (8, 2) exception.
#[test]
fn the_growth_zone_grid_matches_the_account() {
    let runs = data("grow");
    let find = |g: f64, d: f64| {
        runs.iter()
            .find(|r| {
                r.scene
                    .growth
                    .as_ref()
                    .is_some_and(|x| x.gamma == g && x.delta == d)
            })
            .unwrap()
    };
    let spread = |d: f64| {
        let l: Vec<f64> = [4.0, 8.0, 12.0]
            .iter()
            .map(|&g| final_length(find(g, d)))
            .collect();
        l.iter().cloned().fold(f64::MIN, f64::max) - l.iter().cloned().fold(f64::MAX, f64::min)
    };
    assert!(spread(6.0) < 0.2, "{}", spread(6.0));
    assert!(
        spread(2.0) > 3.0 * spread(6.0),
        "{} {}",
        spread(2.0),
        spread(6.0)
    );
    let longest = runs
        .iter()
        .max_by(|a, b| final_length(a).total_cmp(&final_length(b)))
        .unwrap();
    let g = longest.scene.growth.as_ref().unwrap();
    assert_eq!((g.gamma, g.delta), (8.0, 2.0));
    let early: Vec<f64> = [4.0, 8.0, 12.0]
        .iter()
        .map(|&g| length_at(find(g, 2.0), 0.1))
        .collect();
    assert!(early.windows(2).all(|w| w[1] > w[0]), "{early:?}");
    for gamma in [4.0, 8.0, 12.0] {
        let (a, b) = (roundness(find(gamma, 6.0)), roundness(find(gamma, 2.0)));
        assert!(a < b, "Γ = {gamma}: δ = 6 rms {a} against δ = 2 rms {b}");
    }
}

/// RMS distance of the back half of the final retina (z > 12 mm) from its best circle
/// centred on the axis.
fn roundness(r: &RunData) -> f64 {
    let (z, rr) = (col(r, 1.0, "z_retina"), col(r, 1.0, "r_retina"));
    let pts: Vec<(f64, f64)> = z.into_iter().zip(rr).filter(|p| p.0 > 12.0).collect();
    // (z − c)² + r² = R²  ⇔  2 c z + k = z² + r², k = R² − c²: least squares in (c, k).
    let n = pts.len() as f64;
    let (sz, szz) = (
        pts.iter().map(|p| p.0).sum::<f64>(),
        pts.iter().map(|p| p.0 * p.0).sum::<f64>(),
    );
    let b: Vec<f64> = pts.iter().map(|p| p.0 * p.0 + p.1 * p.1).collect();
    let (sb, szb) = (
        b.iter().sum::<f64>(),
        pts.iter().zip(&b).map(|(p, b)| p.0 * b).sum::<f64>(),
    );
    let det = 2.0 * szz * n - 2.0 * sz * sz;
    let c = (szb * n - sz * sb) / det;
    let k = (2.0 * szz * sb - 2.0 * sz * szb) / det;
    let radius = (k + c * c).sqrt();
    (pts.iter()
        .map(|p| ((p.0 - c).hypot(p.1) - radius).powi(2))
        .sum::<f64>()
        / n)
        .sqrt()
}

#[test]
fn plot_draws_an_elastic_and_a_growth_run() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, grow) = small_runs(dir.path());
    let r = ok(&["plot", s(&solve)]);
    assert!(r.stdout.contains("2 files drawn"), "{}", r.stdout);
    let (w, h, colours) = png_stats(&solve.join("plots/fields.png"));
    assert!(w > 1000 && h > 600 && colours > 20);
    ok(&["plot", s(&grow), "--out", s(&dir.path().join("g")), "-q"]);
    for f in ["shells", "profiles", "timeline", "stimulus"] {
        assert!(
            png_stats(&dir.path().join(format!("g/{f}.png"))).2 > 20,
            "{f}"
        );
        let svg = std::fs::read_to_string(dir.path().join(format!("g/{f}.svg"))).unwrap();
        assert!(svg.trim_end().ends_with("</svg>"), "{f}.svg");
    }
    // The run is read back, not recomputed: its timeline is history.csv (scenes/const.toml
    // asks for 100 history points), ending where series.csv ends.
    let run = rundata::read(&grow).unwrap();
    assert_eq!(run.timeline().len(), 101);
    let (_, series) = csv_cells(&grow.join("series.csv"));
    let last: f64 = series.last().unwrap()[1].parse().unwrap();
    assert_eq!(run.timeline().last().unwrap().axial_length, last);
    assert_bad(
        &eyeshell(&["plot", s(&dir.path().join("none"))]),
        "not an eyeshell run directory",
        "plot none",
    );
}

/// Several growth runs are drawn together (axial length, refraction_D, peripheral refraction),
/// each named by its directory; without --out, or with a run that does not grow, it is bad
/// input and nothing is written.
#[test]
fn plot_draws_several_growth_runs_together() {
    let dir = tempfile::tempdir().unwrap();
    let (solve, grow) = small_runs(dir.path());
    let wider = dir.path().join("wider-gamma");
    ok(&[
        "grow",
        "scenes/const.toml",
        "--set",
        "solver.nodes=21",
        "--set",
        "solver.rtol=1e-3",
        "--set",
        "growth.Gamma=12",
        "--out",
        s(&wider),
        "--quiet",
    ]);
    let out = dir.path().join("compare");
    let r = ok(&["plot", s(&grow), s(&wider), "--out", s(&out)]);
    assert!(
        r.stdout.contains("2 files drawn from 2 runs"),
        "{}",
        r.stdout
    );
    let (w, h, colours) = png_stats(&out.join("compare.png"));
    assert!(w > 2000 && h > 500 && colours > 20, "{w} {h} {colours}");
    let svg = std::fs::read_to_string(out.join("compare.svg")).unwrap();
    for needle in [
        "\ngrow\n",
        "\nwider-gamma\n",
        "refraction_D (D)",
        "relative to the pole (D)",
    ] {
        assert!(svg.contains(needle), "{needle} not in compare.svg");
    }
    let nothing = dir.path().join("nothing");
    assert_bad(
        &eyeshell(&["plot", s(&grow), s(&wider)]),
        "give it with --out OUT",
        "plot two runs without --out",
    );
    assert_bad(
        &eyeshell(&["plot", s(&grow), s(&solve), "--out", s(&nothing)]),
        "is not a growth run",
        "plot a growth and an elastic run together",
    );
    assert!(!nothing.exists());
}

/// Ctrl-C (SIGINT) during `eyeshell figures`: the runs waiting for a core never start (all
/// twelve wait at once, so a run that only checked for the interruption before it queued
/// would start anyway), the running ones finish, and the exit is 1 with one line saying
/// where the runs so far are. About 0.5 s.
#[test]
fn ctrl_c_during_figures_starts_no_waiting_run() {
    let dir = tempfile::tempdir().unwrap();
    let (mut child, mut stderr, _) = spawn_in_own_group(
        dir.path(),
        &["figures", "--out", "f", "--jobs", "2"],
        "eyeshell: ",
    );
    let start = std::time::Instant::now();
    let killed = std::process::Command::new("kill")
        .args(["-INT", "--", &format!("-{}", child.id())])
        .status()
        .unwrap();
    assert!(killed.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(1), "{rest}");
    let last = rest.lines().last().unwrap();
    assert!(
        last.starts_with("eyeshell: error: interrupted during scenes/")
            && last.ends_with("the runs so far are in f/data"),
        "{rest}"
    );
    // One run had finished and at most two were running (--jobs 2; a third may have started
    // before the signal came): of the twelve, at least eight never started.
    let not_run = rest.lines().filter(|l| l.ends_with(" not run")).count();
    assert!(not_run >= 8, "{not_run} not run:\n{rest}");
    assert!(start.elapsed().as_secs_f64() < 5.0, "{rest}");
    assert!(!dir.path().join("f/index.html").exists());
}
