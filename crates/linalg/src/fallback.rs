//! A fast solver backed by a robust one: the first factorises while it can, the second
//! (made on first need) takes over for any factorisation the first reports as singular,
//! e.g. an unpivoted elimination whose pivot is too small ([`super::SchurSolver`]).

use super::{Csr, DirectSolver, LinalgError};

/// Makes the backing solver on first need.
pub type MakeSolver = Box<dyn Fn() -> Result<Box<dyn DirectSolver>, LinalgError>>;

/// [`DirectSolver`] that tries `fast` first and falls back to `robust`, per factorisation.
pub struct Fallback {
    fast: Box<dyn DirectSolver>,
    make_robust: MakeSolver,
    robust: Option<Box<dyn DirectSolver>>,
    /// Which one holds the last factorisation.
    using_robust: bool,
    /// Factorisations the robust solver took over.
    fallbacks: usize,
}

impl Fallback {
    pub fn new(fast: Box<dyn DirectSolver>, make_robust: MakeSolver) -> Self {
        Fallback {
            fast,
            make_robust,
            robust: None,
            using_robust: false,
            fallbacks: 0,
        }
    }
}

impl DirectSolver for Fallback {
    fn factor(&mut self, a: &Csr) -> Result<(), LinalgError> {
        self.using_robust = false;
        match self.fast.factor(a) {
            Err(LinalgError::Singular(_)) => {}
            other => return other,
        }
        let robust = match &mut self.robust {
            Some(r) => r,
            None => self.robust.insert((self.make_robust)()?),
        };
        robust.factor(a)?;
        self.using_robust = true;
        self.fallbacks += 1;
        Ok(())
    }

    fn solve(&mut self, b: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        match (&mut self.robust, self.using_robust) {
            (Some(r), true) => r.solve(b, x),
            _ => self.fast.solve(b, x),
        }
    }

    fn fallbacks(&self) -> usize {
        self.fallbacks
    }
}
