//! [`Variant`]: an entry with an erratum read as printed or as corrected (the closed-form
//! `S` and `N` and Table 2 both take it).

/// Which reading of an entry with an erratum to evaluate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Variant {
    /// Exactly as printed in the preprint.
    Printed,
    /// With the smallest correction that makes it agree with the generic engine.
    #[default]
    Corrected,
}
