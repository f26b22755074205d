//! The contract between validation cases and the runner: a case computes named metrics, each
//! with an independent reference and a check.

/// How a metric's value is judged against its reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Check {
    /// Passes when `|value − reference| ≤ tol`.
    Abs(f64),
    /// Passes when `|value − reference| ≤ tol · |reference|`.
    Rel(f64),
    /// Passes when `lo ≤ value ≤ hi` (the reference is informative only, e.g. the exact value
    /// the interval brackets).
    Between(f64, f64),
    /// Passes when `value == reference` exactly (counts).
    Exact,
}

/// One measured quantity of a case.
#[derive(Clone, Debug, PartialEq)]
pub struct Metric {
    /// Short name, unique within its case (e.g. `"T_x2"`, `"level3.faces"`).
    pub name: String,
    /// The value computed.
    pub value: f64,
    /// The independent reference (thesis table, analytic value, brute force).
    pub reference: f64,
    /// How `value` is judged against `reference`.
    pub check: Check,
}

impl Metric {
    /// A metric.
    pub fn new(name: impl Into<String>, value: f64, reference: f64, check: Check) -> Self {
        Self {
            name: name.into(),
            value,
            reference,
            check,
        }
    }
}

/// A validation case: a named computation producing metrics.
pub struct Case {
    /// Identifier, e.g. `"V1-table-6.1"`; also the snapshot file name.
    pub name: &'static str,
    /// One line: what is checked and against what reference.
    pub description: &'static str,
    /// Computes the metrics; `Err` (a message) when the computation itself fails.
    pub run: Box<dyn Fn() -> Result<Vec<Metric>, String> + std::panic::RefUnwindSafe + Send + Sync>,
}
