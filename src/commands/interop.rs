//! `eyeshell export` and `compare`: runs as other people's files, and against them.

use eyeshell::Error;

use crate::args::{CompareArgs, ExportArgs};
use crate::{out, plural};

pub(crate) fn cmd_export(a: &ExportArgs) -> Result<(), Error> {
    use eyeshell::interop::export::{export, Format};
    let mut jobs = Vec::new();
    if let Some(p) = &a.mat {
        jobs.push((
            p,
            Format::Mat {
                compress: a.compress,
            },
        ));
    }
    if let Some(p) = &a.npz {
        jobs.push((p, Format::Npz));
    }
    if a.mat.is_some() && a.mat == a.npz {
        return Err(Error::input(
            eyeshell::Subject::Argument("--npz".into()),
            format!(
                "--mat and --npz are both {}: give two different outputs",
                a.mat
                    .as_deref()
                    .unwrap_or_else(|| std::path::Path::new(""))
                    .display()
            ),
        ));
    }
    // Every target is checked before anything is written.
    for (path, format) in &jobs {
        eyeshell::interop::export::precheck(&a.run, path, *format, a.force)?;
    }
    for (path, format) in jobs {
        let done = export(&a.run, path, format, a.force)?;
        if !a.quiet {
            let what = if done.growth {
                format!(
                    "{} file{} (one per output time)",
                    done.files.len(),
                    plural(done.files.len())
                )
            } else {
                "1 file".to_string()
            };
            out(&format!(
                "eyeshell: exported {} ({} nodes) to {}: {}\n",
                crate::shown(&a.run),
                done.nodes,
                crate::shown(&done.path),
                what
            ));
        }
    }
    Ok(())
}

pub(crate) fn cmd_compare(a: &CompareArgs) -> Result<(), Error> {
    use eyeshell::interop::compare::{compare_paths, format_reports};
    for (name, v) in [("--tol", a.tol), ("--rtol", a.rtol)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::input(
                eyeshell::Subject::Argument(name.into()),
                format!(
                    "{name} = {}: must be a finite number ≥ 0",
                    eyeshell::text::number(v)
                ),
            )
            .with_value(eyeshell::text::number(v))
            .with_origin(eyeshell::Origin::Argument));
        }
    }
    let reports = compare_paths(&a.run, &a.references, a.tol, a.rtol, a.field.as_ref())?;
    let failed: Vec<_> = reports
        .iter()
        .flat_map(|r| {
            r.fields
                .iter()
                .filter(|f| f.failures > 0)
                .map(move |f| (r, f))
        })
        .collect();
    if !a.quiet {
        out(&format_reports(&reports, a.tol, a.rtol));
    }
    if let Some((r, worst)) = failed
        .iter()
        .max_by(|x, y| x.1.worst_ratio.total_cmp(&y.1.worst_ratio))
    {
        return Err(Error::failed(eyeshell::Stage::File, format!(
            "{} field comparison{} beyond |Δ| ≤ {} + {}·|ref|; worst: {} in {} (max |Δ| {:.3e} at {} = {})",
            failed.len(),
            plural(failed.len()),
            eyeshell::text::number(a.tol),
            eyeshell::text::number(a.rtol),
            worst.field,
            r.reference,
            worst.max_abs,
            r.coordinate,
            eyeshell::text::number(worst.at_abs)
        )));
    }
    Ok(())
}
