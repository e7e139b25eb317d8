//! The quantities eyeshell reports of the eye, each declared once: its name (the column of
//! series.csv, history.csv and sweep.csv, the key of summary.json's `final`, of a sweep
//! run's result.json, of population.json and of the Python frames), its unit, what it is,
//! how it is computed, and the function that takes it from a [`SeriesRow`]. Every file,
//! frame, statistic, axis label and docs/guide/outputs.md is made from [`quantities`]; to
//! add a column, add its entry to [`EYE`] (and, if it is a new measure, its computation
//! beside the others in [`crate::model::stimulus::EyeMeasure`]).
//!
//! The table is the core's because the quantities are the model's (docs/MODEL.md §6): it
//! is plain data and functions, with no file or format, and the files crate lays it out
//! into each file. [`register_for_tests`] appends an entry at run time for the tests that
//! check that every output derives from the table; nothing else calls it.

use std::sync::RwLock;

use crate::growth::SeriesRow;

/// One cell of an output: a number, or a word (the class).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cell {
    Number(f64),
    Text(&'static str),
}

impl Cell {
    /// The number (NaN for a word).
    pub fn number(self) -> f64 {
        match self {
            Cell::Number(x) => x,
            Cell::Text(_) => f64::NAN,
        }
    }
}

/// What kind of values a quantity takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A real number (NaN where it could not be computed).
    Number,
    /// One of a fixed set of words ([`crate::model::stimulus::Refraction::as_str`]).
    Class,
}

/// One output quantity of the eye at one time.
#[derive(Clone, Copy, Debug)]
pub struct Quantity {
    /// The column name, the same in every file and frame.
    pub name: &'static str,
    /// The unit as a plot's axis writes it ("mm", "D"); empty for a class.
    pub unit: &'static str,
    /// What it is, in a phrase (a plot's title, a docs line).
    pub description: &'static str,
    /// How it is computed (docs/guide/outputs.md).
    pub computed: &'static str,
    pub kind: Kind,
    /// Whether files written before it existed lack it (a sweep run's result.json): read
    /// back as NaN there instead of refusing the file.
    pub added_later: bool,
    /// Its value in a row of the series.
    pub of: fn(&SeriesRow) -> Cell,
}

impl Quantity {
    /// The axis label of a plot: `name (unit)`, or the name alone without a unit.
    pub fn label(&self) -> String {
        if self.unit.is_empty() {
            self.name.to_string()
        } else {
            format!("{} ({})", self.name, self.unit)
        }
    }

    /// Its value in `row`.
    pub fn value(&self, row: &SeriesRow) -> Cell {
        (self.of)(row)
    }
}

/// The time, the first column of series.csv and history.csv (docs/MODEL.md §5: t in units
/// of the growth time scale, years with time.unit).
pub const TIME: Quantity = Quantity {
    name: "t",
    unit: "",
    description: "the time of the row",
    computed: "the output time (the scene's output and history times), in the scene's time scale (years when the scene sets a time unit; then an `age` column follows the others)",
    kind: Kind::Number,
    added_later: false,
    of: |r| Cell::Number(r.t),
};

/// The measures of the eye at the posterior pole, in their columns' order (docs/MODEL.md
/// §6).
pub const EYE: [Quantity; 8] = [
    Quantity {
        name: "axial_length",
        unit: "mm",
        description: "axial length",
        computed: "z of the retina at the posterior pole (docs/MODEL.md §6), from the elastic solution of the loaded, grown shell",
        kind: Kind::Number,
        added_later: false,
        of: |r| Cell::Number(r.axial_length),
    },
    Quantity {
        name: "equatorial_radius",
        unit: "mm",
        description: "equatorial radius",
        computed: "the largest r of the retina over the meridian",
        kind: Kind::Number,
        added_later: false,
        of: |r| Cell::Number(r.equatorial_radius),
    },
    Quantity {
        name: "retina_minus_blue",
        unit: "mm",
        description: "retina behind the blue focal surface",
        computed: "the distance of the pole's retina behind the blue (short-wavelength) best-focus surface along its polar ray (negative: in front of it)",
        kind: Kind::Number,
        added_later: false,
        of: |r| Cell::Number(r.retina_minus_blue),
    },
    Quantity {
        name: "retina_minus_red",
        unit: "mm",
        description: "retina behind the red focal surface",
        computed: "the same for the red (long-wavelength) best-focus surface",
        kind: Kind::Number,
        added_later: false,
        of: |r| Cell::Number(r.retina_minus_red),
    },
    Quantity {
        name: "class",
        unit: "",
        description: "refractive class",
        computed: "hyperopic, emmetropic or myopic by the scene's classification: the pole's retina against the blue and red surfaces, or refraction_D against the scene's myopia and hyperopia thresholds in dioptres (unknown where refraction_D is NaN)",
        kind: Kind::Class,
        added_later: false,
        of: |r| Cell::Text(r.class.as_str()),
    },
    Quantity {
        name: "refraction_D",
        unit: "D",
        description: "refraction at the pole",
        computed: "the spectacle power at 12 mm (at the scene's refraction wavelength) that brings the naked eye's on-axis best focus onto the retina; NaN for an elastic run and beyond -25 to +25 D",
        kind: Kind::Number,
        added_later: true,
        of: |r| Cell::Number(r.refraction_d),
    },
    Quantity {
        name: "drive",
        unit: "mm",
        description: "growth rule's drive at the pole",
        computed: "the scene's growth rule at the pole's retina: growth there runs at g_c · [drive]⁺ (docs/MODEL.md §6); for the paper's rule the depth of the blue surface behind the retina (minus retina_minus_blue); NaN for an elastic run",
        kind: Kind::Number,
        added_later: true,
        of: |r| Cell::Number(r.drive),
    },
    Quantity {
        name: "defocus_D",
        unit: "D",
        description: "defocus at the pole",
        computed: "the defocus of the stimulus image at the pole through the lenses worn, as a vergence at the corneal vertex (positive: the image behind the retina); NaN unless the growth rule reads defocus (the defocus rule)",
        kind: Kind::Number,
        added_later: true,
        of: |r| Cell::Number(r.defocus_d),
    },
];

/// Entries appended by [`register_for_tests`] (none in a program).
static REGISTERED: RwLock<Vec<Quantity>> = RwLock::new(Vec::new());

/// Append `q` to the measures of the eye, for this process. Only the tests call it: they
/// add a column through the table alone and find it in every file and frame.
#[doc(hidden)]
pub fn register_for_tests(q: Quantity) {
    REGISTERED
        .write()
        .unwrap_or_else(|e| e.into_inner())
        .push(q);
}

/// The measures of the eye, in their columns' order: [`EYE`] (and what the tests
/// registered).
pub fn quantities() -> Vec<Quantity> {
    let registered = REGISTERED.read().unwrap_or_else(|e| e.into_inner());
    EYE.iter().chain(registered.iter()).copied().collect()
}

/// The columns of series.csv and history.csv: [`TIME`], then the [`quantities`].
pub fn series_quantities() -> Vec<Quantity> {
    std::iter::once(TIME).chain(quantities()).collect()
}

/// The quantity named `name` among the [`series_quantities`].
pub fn quantity(name: &str) -> Option<Quantity> {
    series_quantities().into_iter().find(|q| q.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::stimulus::Refraction;

    #[test]
    fn each_quantity_reads_its_own_field() {
        let row = SeriesRow {
            t: 0.5,
            axial_length: 21.0,
            equatorial_radius: 11.0,
            retina_minus_blue: 0.1,
            retina_minus_red: -0.2,
            class: Refraction::Myopic,
            refraction_d: -1.5,
            drive: 0.25,
            defocus_d: 0.75,
        };
        let cells: Vec<Cell> = series_quantities().iter().map(|q| q.value(&row)).collect();
        assert_eq!(
            cells,
            [
                Cell::Number(0.5),
                Cell::Number(21.0),
                Cell::Number(11.0),
                Cell::Number(0.1),
                Cell::Number(-0.2),
                Cell::Text("myopic"),
                Cell::Number(-1.5),
                Cell::Number(0.25),
                Cell::Number(0.75),
            ]
        );
        let names: Vec<&str> = series_quantities().iter().map(|q| q.name).collect();
        assert_eq!(
            names,
            [
                "t",
                "axial_length",
                "equatorial_radius",
                "retina_minus_blue",
                "retina_minus_red",
                "class",
                "refraction_D",
                "drive",
                "defocus_D"
            ]
        );
        assert_eq!(
            quantity("refraction_D").unwrap().label(),
            "refraction_D (D)"
        );
        assert_eq!(quantity("class").unwrap().label(), "class");
        assert!(quantity("age").is_none());
    }
}
