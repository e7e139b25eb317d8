//! The default optics' refraction tables are kept in crates/core/src/model/default_tables.rs
//! instead of being traced by every run (docs/MODEL.md §10, "Refraction"): this checks them
//! against a fresh trace, and `EYESHELL_BLESS=1` rewrites them from one.

use eyeshell_core::model::eyewear::{
    default_tables, trace_peripheral_table, trace_refraction_table,
};
use eyeshell_core::model::optics::OpticsSpec;

const FILE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/src/model/default_tables.rs");

/// A Rust literal that reads back as `x` exactly (Debug is the shortest round trip).
fn literal(x: f64) -> String {
    if x.is_nan() {
        "f64::NAN".into()
    } else {
        let s = format!("{x:?}");
        if s.contains('.') || s.contains('e') || s.contains("inf") {
            s
        } else {
            format!("{s}.0")
        }
    }
}

#[test]
fn default_refraction_tables_are_a_fresh_trace() {
    let spec = OpticsSpec::default();
    let pole = trace_refraction_table(&spec, 0.0).unwrap();
    let peripheral = trace_peripheral_table(&spec, 0.0).unwrap();
    if std::env::var_os("EYESHELL_BLESS").is_some() {
        let mut out = String::from(
            "//! The refraction tables of the default optics (the Atchison 2006 eye, a 3 mm pupil, the\n\
             //! mean sphere, 555 nm; fields every 5° to 40°), as traced by\n\
             //! `eyeshell_core::model::eyewear::trace_refraction_table` and `trace_peripheral_table`.\n\
             //! Generated: `EYESHELL_BLESS=1 cargo test --release -p eyeshell-core --test numerics\n\
             //! default_tables`, which without EYESHELL_BLESS checks them against a fresh trace.\n\n",
        );
        out += &format!(
            "pub(super) const WAVELENGTH_NM: f64 = {};\n\n",
            literal(pole.wavelength_nm)
        );
        out += &format!(
            "pub(super) const POLE_FOCI: [f64; {}] = [\n",
            pole.foci.len()
        );
        for z in &pole.foci {
            out += &format!("    {},\n", literal(*z));
        }
        out += "];\n\n";
        let (nf, np) = (peripheral.fields.len(), peripheral.powers.len());
        out += &format!("pub(super) const FIELDS: [f64; {nf}] = [\n");
        for f in &peripheral.fields {
            out += &format!("    {},\n", literal(*f));
        }
        out += "];\n\n";
        out += &format!("pub(super) const PERIPHERAL_FOCI: [[(f64, f64); {np}]; {nf}] = [\n");
        for row in &peripheral.foci {
            out += "    [\n";
            for (z, r) in row {
                out += &format!("        ({}, {}),\n", literal(*z), literal(*r));
            }
            out += "    ],\n";
        }
        out += "];\n\n";
        out += &format!("pub(super) const PERIPHERAL_BETWEEN: [&[(f64, (f64, f64))]; {nf}] = [\n");
        for row in &peripheral.between {
            out += "    &[\n";
            for (f, (z, r)) in row {
                out += &format!(
                    "        ({}, ({}, {})),\n",
                    literal(*f),
                    literal(*z),
                    literal(*r)
                );
            }
            out += "    ],\n";
        }
        out += "];\n";
        std::fs::write(FILE, out).unwrap();
        return;
    }
    let (kept_pole, kept_peripheral) = default_tables();
    let hint = "rewrite them with EYESHELL_BLESS=1 cargo test --release -p eyeshell-core --test numerics default_tables";
    assert_eq!(kept_pole.powers, pole.powers);
    assert_eq!(kept_pole.wavelength_nm, pole.wavelength_nm);
    assert_eq!(kept_pole.vertex, pole.vertex);
    // The same trace to rounding: a machine whose libm rounds differently moves a focus by
    // far less than 1e-9 mm (the refraction's 0.01 D is about 0.004 mm).
    for (k, (a, b)) in kept_pole.foci.iter().zip(&pole.foci).enumerate() {
        assert!(
            (a - b).abs() <= 1e-9,
            "pole focus {k}: kept {a}, traced {b}: {hint}"
        );
    }
    assert_eq!(kept_peripheral.fields, peripheral.fields, "{hint}");
    // The powers traced between the grid's, where the cubic missed: the same, to rounding.
    assert_eq!(
        kept_peripheral.between.len(),
        peripheral.between.len(),
        "{hint}"
    );
    for (i, (ka, kb)) in kept_peripheral
        .between
        .iter()
        .zip(&peripheral.between)
        .enumerate()
    {
        assert_eq!(ka.len(), kb.len(), "field {i}: {hint}");
        for ((fa, a), (fb, b)) in ka.iter().zip(kb) {
            assert!(
                fa == fb && (a.0 - b.0).abs() <= 1e-9 && (a.1 - b.1).abs() <= 1e-9,
                "field {i}, power {fa}: kept {a:?}, traced {b:?}: {hint}"
            );
        }
    }
    assert_eq!(kept_peripheral.powers, peripheral.powers, "{hint}");
    for (i, (ra, rb)) in kept_peripheral
        .foci
        .iter()
        .zip(&peripheral.foci)
        .enumerate()
    {
        assert_eq!(ra.len(), rb.len());
        for (k, (a, b)) in ra.iter().zip(rb).enumerate() {
            let same = |x: f64, y: f64| (x.is_nan() && y.is_nan()) || (x - y).abs() <= 1e-9;
            assert!(
                same(a.0, b.0) && same(a.1, b.1),
                "field {i}, power {k}: kept {a:?}, traced {b:?}: {hint}"
            );
        }
    }
}

/// The default optics read the kept tables (not a trace), and read them as the traced
/// tables do.
#[test]
fn the_default_optics_read_the_kept_tables() {
    let spec = OpticsSpec::default();
    let kept = eyeshell_core::model::eyewear::refraction_table(&spec).unwrap();
    let kept_peripheral = eyeshell_core::model::eyewear::peripheral_table_at(&spec, 0.0).unwrap();
    assert!(std::sync::Arc::ptr_eq(&kept, &default_tables().0));
    assert!(std::sync::Arc::ptr_eq(
        &kept_peripheral,
        &default_tables().1
    ));
    // Any other optics are traced: a 4 mm pupil is not the kept table.
    let other = OpticsSpec {
        pupil: 4.0,
        ..OpticsSpec::default()
    };
    let traced_other = eyeshell_core::model::eyewear::refraction_table(&other).unwrap();
    assert!(!std::sync::Arc::ptr_eq(&traced_other, &default_tables().0));
    assert_ne!(traced_other.foci, kept.foci);
    let traced = trace_refraction_table(&spec, 0.0).unwrap();
    for z in [22.0, 22.5, 23.0, 23.5, 24.0] {
        let (a, b) = (kept.refraction(z).unwrap(), traced.refraction(z).unwrap());
        assert!(
            (a - b).abs() < 1e-9,
            "retina at {z}: kept {a} D, traced {b} D"
        );
    }
    assert_eq!(kept_peripheral.fields.len(), 9);
}
