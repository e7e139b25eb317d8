//! The paper's refinement check (being written).
