//! Schematic eyes built in, each as its source gives it (docs/optics.md cites every number and
//! says which were checked at the source and which were read elsewhere).

use crate::medium::{Dispersion, Grin, GrinDispersion, Medium};
use crate::surface::Surface;
use crate::system::{Element, OpticalSystem};

/// A built-in eye: the name `optics.eye` selects it by (and older names it answers to), the
/// system as its source gives it, and the wavelengths its dispersion holds for. Every list
/// of the built-in eyes (the scene key's names, [`builtin`], [`wavelength_range`], the
/// eyes' tests) is read from [`REGISTRY`], so that an eye added there is selectable
/// everywhere.
#[derive(Debug, Clone, Copy)]
pub struct BuiltinEye {
    pub name: &'static str,
    /// Other names `builtin` accepts for it.
    pub aliases: &'static [&'static str],
    pub build: fn() -> OpticalSystem,
    pub wavelengths: WavelengthRange,
}

/// The built-in eyes.
pub const REGISTRY: [BuiltinEye; 3] = [
    BuiltinEye {
        name: "atchison-2006",
        aliases: &[],
        build: atchison_2006,
        // Atchison & Smith (2005)'s Cauchy laws, fitted to visible data and extended by
        // their authors into the near infrared, where ocular media were measured to 1100 nm.
        wavelengths: WavelengthRange {
            lo: 380.0,
            hi: 1100.0,
            source: "its Cauchy laws (Atchison & Smith 2005) hold over the visible and the near infrared to 1100 nm",
        },
    },
    BuiltinEye {
        name: "liou-brennan-1997",
        aliases: &[],
        build: liou_brennan_1997,
        // The source's own range; its quadratic shift turns at 757 nm, beyond which the
        // eye's power would rise again with wavelength.
        wavelengths: WavelengthRange {
            lo: 380.0,
            hi: 750.0,
            source: "Liou & Brennan (1997) give their dispersion for 380-750 nm",
        },
    },
    BuiltinEye {
        name: "escudero-sanz-navarro-1999",
        aliases: &["navarro-1999"],
        build: escudero_sanz_navarro_1999,
        // Indices tabulated at 458-632.8 nm, read through a Cauchy fit: the visible range
        // is as far as the fit is carried.
        wavelengths: WavelengthRange {
            lo: 380.0,
            hi: 750.0,
            source: "the source tabulates its indices at 458-632.8 nm; their Cauchy fit is carried over the visible range only",
        },
    },
];

/// The names of the built-in eyes, in the order of [`REGISTRY`].
pub const BUILTIN: [&str; REGISTRY.len()] = {
    let mut names = [""; REGISTRY.len()];
    let mut i = 0;
    while i < REGISTRY.len() {
        names[i] = REGISTRY[i].name;
        i += 1;
    }
    names
};

/// The wavelengths (nm) a built-in eye's dispersion holds for: where its source gives it
/// (or fits it to its data) and every medium's index falls with wavelength, so that the
/// eye's power does too (docs/optics.md, "Built-in eyes and their sources").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WavelengthRange {
    pub lo: f64,
    pub hi: f64,
    /// Where the range comes from, for messages.
    pub source: &'static str,
}

/// The built-in eye called `name` (or one of its aliases).
pub fn find(name: &str) -> Option<BuiltinEye> {
    REGISTRY
        .iter()
        .find(|e| e.name == name || e.aliases.contains(&name))
        .copied()
}

/// The wavelength range of the built-in eye `name`.
pub fn wavelength_range(name: &str) -> Option<WavelengthRange> {
    find(name).map(|e| e.wavelengths)
}

/// A built-in eye by name (or alias).
pub fn builtin(name: &str) -> Option<OpticalSystem> {
    find(name).map(|e| (e.build)())
}

fn air() -> Medium {
    Medium::constant("air", 1.0)
}

/// The built-in numbers are fixed, so the system is assembled directly; the tests check each
/// eye with `OpticalSystem::new`'s validation.
fn build(name: &str, elements: Vec<Element>, pupil: f64) -> OpticalSystem {
    OpticalSystem {
        name: name.to_string(),
        object: air(),
        elements,
        pupil_position: Some(pupil),
        retina: None,
        origin: 0.0,
    }
}

/// Liou & Brennan (1997), JOSA A 14(8):1684–1695: four aspheric surfaces and a GRIN lens in
/// two halves, n(w, z) = n₀₀ + n₀₁z + n₀₂z² + n₁₀w² (w² = x² + y², z from each half's front),
/// at 555 nm, every medium shifted by 0.0512 − 0.1455λ + 0.0961λ² (λ in µm). Equivalent power
/// 60.35 D, axial length 23.95 mm. The pupil lies at the lens's front vertex (the source
/// decentres it 0.5 mm nasally; here it is centred, as the axial symmetry requires).
pub fn liou_brennan_1997() -> OpticalSystem {
    let lb = |n: f64| Dispersion::LiouBrennan { n555: n };
    let shift = Some(GrinDispersion::Uniform {
        law: Dispersion::LiouBrennan { n555: 0.0 },
        reference_nm: None,
    });
    build(
        "liou-brennan-1997",
        vec![
            Element::new(
                Surface::new("anterior cornea", 7.77, -0.18),
                0.50,
                Medium::homogeneous("cornea", lb(1.376)),
            ),
            Element::new(
                Surface::new("posterior cornea", 6.40, -0.60),
                3.16,
                Medium::homogeneous("aqueous", lb(1.336)),
            ),
            Element::new(
                Surface::new("anterior lens", 12.40, -0.94),
                1.59,
                Medium::grin(
                    "lens (anterior half)",
                    Grin {
                        coefficients: vec![vec![1.368, 0.049057, -0.015427], vec![-0.001978]],
                        origin: 0.0,
                        dispersion: shift.clone(),
                    },
                ),
            ),
            Element::new(
                Surface::plane("lens equator"),
                2.43,
                Medium::grin(
                    "lens (posterior half)",
                    Grin {
                        coefficients: vec![vec![1.407, 0.0, -0.006605], vec![-0.001978]],
                        origin: 0.0,
                        dispersion: shift,
                    },
                ),
            ),
            Element::new(
                Surface::new("posterior lens", -8.10, 0.96),
                16.27,
                Medium::homogeneous("vitreous", lb(1.336)),
            ),
        ],
        3.66,
    )
}

/// Escudero-Sanz & Navarro (1999), JOSA A 16(8):1881–1891: the wide-angle schematic eye,
/// conic surfaces and a homogeneous lens; indices tabulated at 458, 543, 589.3 and 632.8 nm,
/// made a law by a three-term Cauchy fit. The stop lies at the lens's front vertex.
pub fn escudero_sanz_navarro_1999() -> OpticalSystem {
    let table = |v: [f64; 4]| {
        Dispersion::Tabulated(vec![
            (458.0, v[0]),
            (543.0, v[1]),
            (589.3, v[2]),
            (632.8, v[3]),
        ])
    };
    build(
        "escudero-sanz-navarro-1999",
        vec![
            Element::new(
                Surface::new("anterior cornea", 7.72, -0.26),
                0.55,
                Medium::homogeneous("cornea", table([1.3828, 1.3777, 1.376, 1.3747])),
            ),
            Element::new(
                Surface::new("posterior cornea", 6.50, 0.0),
                3.05,
                Medium::homogeneous("aqueous", table([1.3445, 1.3391, 1.3374, 1.336])),
            ),
            Element::new(
                Surface::new("anterior lens", 10.2, -3.1316),
                4.0,
                Medium::homogeneous("lens", table([1.4292, 1.4222, 1.42, 1.4183])),
            ),
            Element::new(
                Surface::new("posterior lens", -6.0, -1.0),
                16.3203,
                Medium::homogeneous("vitreous", table([1.3428, 1.3377, 1.336, 1.3347])),
            ),
        ],
        3.60,
    )
    .with_retina(Surface::new("retina", -12.0, 0.0))
}

/// Atchison (2006), Vision Res 46(14):2236–2250, the centred emmetropic (0 D) model: aspheric
/// cornea and lens surfaces and a GRIN lens in two halves whose iso-indicial surfaces are
/// ellipsoids, n = n_c − Δ(ζ²/t² + r²/a²), from 1.371 at the surface to 1.418 at the centre
/// (Δ = 0.047), anterior half t = 1.44 mm, posterior half t = 2.16 mm, a² = 23.04 mm², at
/// 555 nm. Dispersion: each medium's index at 555 nm carried to other wavelengths by the
/// Cauchy coefficients B, C, D of Atchison & Smith's form (read from gkaModelEye, which takes
/// them from Navarro 2014), the lens's interpolated between its surface and centre laws.
/// The stop lies at the lens's front vertex.
pub fn atchison_2006() -> OpticalSystem {
    const REF: f64 = 555.0;
    let law = |n: f64, b: f64, c: f64, d: f64| Dispersion::cauchy_through(n, REF, b, c, d);
    let (ns, nc, delta) = (1.371, 1.418, 0.047);
    let (ta, tp, a2) = (1.44_f64, 2.16_f64, 23.04);
    let lens_dispersion = Some(GrinDispersion::Interpolated {
        surface: law(ns, 6.428455e3, -6.023738e8, 5.824149e13),
        centre: law(nc, 6.521218e3, -6.11066e8, 5.908191e13),
        n_surface: ns,
        n_centre: nc,
        reference_nm: REF,
    });
    build(
        "atchison-2006",
        vec![
            Element::new(
                Surface::new("anterior cornea", 7.77, -0.15),
                0.55,
                Medium::homogeneous("cornea", law(1.376, 6.009687e3, -6.760760e8, 5.908450e13)),
            ),
            Element::new(
                Surface::new("posterior cornea", 6.40, -0.275),
                3.15,
                Medium::homogeneous("aqueous", law(1.3374, 6.070796e3, -7.062305e8, 6.147861e13)),
            ),
            Element::new(
                Surface::new("anterior lens", 11.48, -5.0),
                ta,
                Medium::grin(
                    "lens (anterior half)",
                    Grin {
                        // n_s + 2Δζ/t − Δζ²/t² − Δr²/a², ζ from the anterior vertex.
                        coefficients: vec![
                            vec![ns, 2.0 * delta / ta, -delta / (ta * ta)],
                            vec![-delta / a2],
                        ],
                        origin: 0.0,
                        dispersion: lens_dispersion.clone(),
                    },
                ),
            ),
            Element::new(
                Surface::plane("lens equator"),
                tp,
                Medium::grin(
                    "lens (posterior half)",
                    Grin {
                        coefficients: vec![vec![nc, 0.0, -delta / (tp * tp)], vec![-delta / a2]],
                        origin: 0.0,
                        dispersion: lens_dispersion,
                    },
                ),
            ),
            Element::new(
                Surface::new("posterior lens", -5.90, -2.0),
                16.28,
                Medium::homogeneous("vitreous", law(1.336, 5.560240e3, -5.817391e8, 5.036810e13)),
            ),
        ],
        3.70,
    )
}
