//! colloidsim-analysis (see the crate description).
