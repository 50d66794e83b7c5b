//! Reports: named configurations with their matrices and metrics, as JSON and markdown.

use crate::confusion::ConfusionMatrix;
use crate::error::EvalError;
use crate::matching::{MatchStats, PointCounts};
use crate::metrics::Metrics;
use bodyseg_core::Class;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Version of the `report.json` layout written by [`Report::to_json`]; [`Report::from_json`]
/// reads only this version.
pub const REPORT_VERSION: u32 = 1;

/// One evaluated configuration (a refinement variant such as "M-R-N"): its name, summed
/// match statistics and the metrics derived from them.
///
/// The metrics are always those of the matrix: the fields are private and set together.
#[derive(Clone, Debug, PartialEq)]
pub struct Configuration {
    name: String,
    stats: MatchStats,
    metrics: Metrics,
}

impl Configuration {
    /// A configuration with metrics computed from `stats.confusion`.
    pub fn new(name: impl Into<String>, stats: MatchStats) -> Configuration {
        let metrics = Metrics::from_matrix(&stats.confusion);
        Configuration {
            name: name.into(),
            stats,
            metrics,
        }
    }

    /// The configuration's name ("Reference", "M", ...).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Matrix and point counts.
    pub fn stats(&self) -> &MatchStats {
        &self.stats
    }

    /// The confusion matrix, rows = ground truth, columns = prediction.
    pub fn confusion(&self) -> &ConfusionMatrix {
        &self.stats.confusion
    }

    /// Points left out of or substituted in the evaluation.
    pub fn counts(&self) -> &PointCounts {
        &self.stats.counts
    }

    /// Number of evaluated points.
    pub fn evaluated(&self) -> u64 {
        self.stats.evaluated()
    }

    /// Metrics derived from the confusion matrix.
    pub fn metrics(&self) -> &Metrics {
        &self.metrics
    }
}

/// An ordered list of uniquely named [`Configuration`]s; the first is the reference that
/// the markdown table's change rows compare against.
///
/// JSON (`report.json`, [`Report::to_json`]) holds every configuration's confusion matrix,
/// point counts and metrics. The matrices are authoritative: on reading, the metrics are
/// recomputed from them and the stored metrics are ignored. Serialize/Deserialize use the
/// same layout, so a report can be embedded in another serde document.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    configurations: Vec<Configuration>,
}

impl Report {
    /// An empty report.
    pub fn new() -> Report {
        Report::default()
    }

    /// Appends a configuration, computing its metrics.
    ///
    /// # Errors
    /// [`EvalError::DuplicateConfiguration`] when the name is taken.
    pub fn push(&mut self, name: impl Into<String>, stats: MatchStats) -> Result<(), EvalError> {
        let name = name.into();
        if self.get(&name).is_some() {
            return Err(EvalError::DuplicateConfiguration { name });
        }
        self.configurations.push(Configuration::new(name, stats));
        Ok(())
    }

    /// The configurations, in insertion order.
    pub fn configurations(&self) -> &[Configuration] {
        &self.configurations
    }

    /// The configuration with this name.
    pub fn get(&self, name: &str) -> Option<&Configuration> {
        self.configurations.iter().find(|c| c.name == name)
    }

    /// The configuration names, in order.
    pub fn names(&self) -> Vec<&str> {
        self.configurations
            .iter()
            .map(|c| c.name.as_str())
            .collect()
    }

    /// Sums shard reports: per configuration name, matrices and point counts are added and
    /// the metrics recomputed. The configurations keep the first report's order; the others
    /// may list them in any order.
    ///
    /// # Errors
    /// [`EvalError::NoReports`] for an empty input, [`EvalError::ConfigurationMismatch`] when
    /// the reports' configuration sets differ, [`EvalError::CountOverflow`] when a sum
    /// exceeds `u64::MAX`.
    pub fn merge<'a>(reports: impl IntoIterator<Item = &'a Report>) -> Result<Report, EvalError> {
        let mut reports = reports.into_iter();
        let first = reports.next().ok_or(EvalError::NoReports)?;
        let mut sums: Vec<(String, MatchStats)> = first
            .configurations
            .iter()
            .map(|c| (c.name.clone(), c.stats.clone()))
            .collect();
        for (offset, report) in reports.enumerate() {
            let same_set = report.configurations.len() == sums.len()
                && sums.iter().all(|(name, _)| report.get(name).is_some());
            if !same_set {
                return Err(EvalError::ConfigurationMismatch {
                    index: offset + 1,
                    want: first.names().into_iter().map(String::from).collect(),
                    got: report.names().into_iter().map(String::from).collect(),
                });
            }
            for (name, sum) in &mut sums {
                let other = report
                    .get(name)
                    .expect("same_set checked that every name is present");
                *sum = sum
                    .checked_add(&other.stats)
                    .ok_or_else(|| EvalError::CountOverflow { name: name.clone() })?;
            }
        }
        Ok(Report {
            configurations: sums
                .into_iter()
                .map(|(name, stats)| Configuration::new(name, stats))
                .collect(),
        })
    }

    /// The report as pretty-printed JSON (`report.json`, FORMATS.md "Reports"):
    ///
    /// ```json
    /// { "version": 1,
    ///   "classes": ["background", "head", ...],
    ///   "configurations": [
    ///     { "name": "Reference",
    ///       "confusion": { "counts": [[...7], ...7] },
    ///       "points": { "evaluated": 0, "pred_unknown": 0, "gt_unknown": 0,
    ///                   "gt_unmatched": 0, "pred_unmatched": 0 },
    ///       "metrics": { "per_class": [{ "class": "background", "present": true,
    ///                                    "support": 0, "predicted": 0, "iou": 0.99,
    ///                                    "precision": 0.99, "recall": 0.99, "f1": 0.99 }, ...],
    ///                    "miou": 0.75, "biou": 0.7, "ap": 0.9, "f1": 0.85 } } ] }
    /// ```
    ///
    /// `classes` names the matrices' row and column order; absent classes' values and empty
    /// means are `null`.
    ///
    /// # Errors
    /// [`EvalError::Json`] if serialization fails (it does not for this layout).
    pub fn to_json(&self) -> Result<String, EvalError> {
        serde_json::to_string_pretty(self).map_err(|source| EvalError::Json { source })
    }

    /// Reads a report written by [`Report::to_json`], recomputing the metrics from the
    /// matrices.
    ///
    /// # Errors
    /// [`EvalError::Json`] for malformed JSON or a missing field; [`EvalError::UnsupportedVersion`],
    /// [`EvalError::ClassOrder`], [`EvalError::DuplicateConfiguration`] and
    /// [`EvalError::InconsistentCounts`] for a well-formed file that this build cannot trust.
    pub fn from_json(json: &str) -> Result<Report, EvalError> {
        let file: ReportFile =
            serde_json::from_str(json).map_err(|source| EvalError::Json { source })?;
        Report::try_from_file(file)
    }

    fn try_from_file(file: ReportFile) -> Result<Report, EvalError> {
        if file.version != REPORT_VERSION {
            return Err(EvalError::UnsupportedVersion {
                got: file.version,
                want: REPORT_VERSION,
            });
        }
        let want = class_names();
        if file.classes != want {
            return Err(EvalError::ClassOrder {
                got: file.classes,
                want,
            });
        }
        let mut report = Report::new();
        for c in file.configurations {
            let matrix_total = c.confusion.total();
            if c.points.evaluated != matrix_total {
                return Err(EvalError::InconsistentCounts {
                    name: c.name,
                    evaluated: c.points.evaluated,
                    matrix_total,
                });
            }
            let stats = MatchStats {
                confusion: c.confusion,
                counts: PointCounts {
                    pred_unknown: c.points.pred_unknown,
                    gt_unknown: c.points.gt_unknown,
                    gt_unmatched: c.points.gt_unmatched,
                    pred_unmatched: c.points.pred_unmatched,
                },
            };
            report.push(c.name, stats)?;
        }
        Ok(report)
    }

    fn to_file(&self) -> ReportFile {
        ReportFile {
            version: REPORT_VERSION,
            classes: class_names(),
            configurations: self
                .configurations
                .iter()
                .map(|c| ConfigurationFile {
                    name: c.name.clone(),
                    confusion: c.stats.confusion.clone(),
                    points: PointsFile {
                        evaluated: c.evaluated(),
                        pred_unknown: c.stats.counts.pred_unknown,
                        gt_unknown: c.stats.counts.gt_unknown,
                        gt_unmatched: c.stats.counts.gt_unmatched,
                        pred_unmatched: c.stats.counts.pred_unmatched,
                    },
                    metrics: Some(c.metrics.clone()),
                })
                .collect(),
        }
    }

    /// The report as markdown, the paper's table layout (`report.md`):
    ///
    /// 1. IoU per class (%) with mIoU, BIoU, AP and F1, one row per configuration and under
    ///    every configuration but the first a change row `Δ vs <first>` in percentage points
    ///    (the difference of the unrounded values, rounded); absent classes and empty means
    ///    print as `–`, and a note under the table names the classes left out of the means.
    /// 2. Precision / recall / F1 per class (%), one row per configuration.
    /// 3. The point counts: evaluated, substituted and unmatched points.
    pub fn to_markdown(&self) -> String {
        let mut out = String::new();
        out.push_str(&self.iou_table());
        out.push('\n');
        out.push_str(&self.prf_table());
        out.push('\n');
        out.push_str(&self.points_table());
        out
    }

    fn iou_table(&self) -> String {
        let mut out = String::from("IoU per class and means (%):\n\n");
        let mut header = vec!["Configuration".to_string()];
        header.extend(TABLE_CLASSES.iter().map(|c| c.title().to_string()));
        header.extend(["mIoU", "BIoU", "AP", "F1"].map(String::from));
        out.push_str(&table_row(&header));
        out.push_str(&separator_row(header.len()));

        let reference = self.configurations.first();
        for (i, c) in self.configurations.iter().enumerate() {
            let values = iou_row_values(&c.metrics);
            let mut row = vec![escape_cell(&c.name)];
            row.extend(values.iter().map(|&v| format_percent(v)));
            out.push_str(&table_row(&row));
            if let Some(reference) = reference.filter(|_| i > 0) {
                let base = iou_row_values(&reference.metrics);
                let mut delta = vec![format!("Δ vs {}", escape_cell(&reference.name))];
                delta.extend(
                    values
                        .iter()
                        .zip(&base)
                        .map(|(&v, &b)| format_delta(v.zip(b).map(|(v, b)| v - b))),
                );
                out.push_str(&table_row(&delta));
            }
        }

        out.push_str(&self.left_out_note());
        out
    }

    /// The note under the IoU table naming the classes left out of the means, or "".
    fn left_out_note(&self) -> String {
        let absent: Vec<(&str, Vec<Class>)> = self
            .configurations
            .iter()
            .map(|c| (c.name.as_str(), c.metrics.absent_classes()))
            .collect();
        if absent.iter().all(|(_, classes)| classes.is_empty()) {
            return String::new();
        }
        let lead = "\nLeft out of mIoU, BIoU, AP and F1 (absent from both prediction and ground truth, shown as –)";
        if let Some((_, first)) = absent
            .first()
            .filter(|(_, first)| absent.iter().all(|(_, classes)| classes == first))
        {
            return format!("{lead}: {}.\n", titles(first));
        }
        let per_configuration: Vec<String> = absent
            .iter()
            .filter(|(_, classes)| !classes.is_empty())
            .map(|(name, classes)| format!("{}: {}", escape_cell(name), titles(classes)))
            .collect();
        format!("{lead}: {}.\n", per_configuration.join("; "))
    }

    fn prf_table(&self) -> String {
        let mut out = String::from("Precision / recall / F1 per class (%):\n\n");
        let mut header = vec!["Configuration".to_string()];
        header.extend(TABLE_CLASSES.iter().map(|c| c.title().to_string()));
        out.push_str(&table_row(&header));
        out.push_str(&separator_row(header.len()));
        for c in &self.configurations {
            let mut row = vec![escape_cell(&c.name)];
            row.extend(TABLE_CLASSES.iter().map(|&class| {
                let m = c.metrics.class(class);
                if m.present {
                    format!(
                        "{} / {} / {}",
                        format_percent(m.precision),
                        format_percent(m.recall),
                        format_percent(m.f1)
                    )
                } else {
                    NONE_CELL.to_string()
                }
            }));
            out.push_str(&table_row(&row));
        }
        out
    }

    fn points_table(&self) -> String {
        let mut out = String::from("Points:\n\n");
        let header = [
            "Configuration",
            "Evaluated",
            "Unknown prediction (scored as background)",
            "Unknown ground truth (not evaluated)",
            "Ground truth without prediction",
            "Prediction without ground truth",
        ]
        .map(String::from);
        out.push_str(&table_row(&header));
        out.push_str(&separator_row(header.len()));
        for c in &self.configurations {
            let n = &c.stats.counts;
            let row = [
                escape_cell(&c.name),
                c.evaluated().to_string(),
                n.pred_unknown.to_string(),
                n.gt_unknown.to_string(),
                n.gt_unmatched.to_string(),
                n.pred_unmatched.to_string(),
            ];
            out.push_str(&table_row(&row));
        }
        out
    }
}

impl Serialize for Report {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.to_file().serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Report {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Report, D::Error> {
        let file = ReportFile::deserialize(deserializer)?;
        Report::try_from_file(file).map_err(serde::de::Error::custom)
    }
}

/// Column order of the paper's tables: body classes, then background.
const TABLE_CLASSES: [Class; 7] = {
    let mut table = [Class::Background; 7];
    let mut i = 0;
    while i < Class::BODY.len() {
        table[i] = Class::BODY[i];
        i += 1;
    }
    table
};

/// What a table cell shows for a class absent from both clouds, or an empty mean.
const NONE_CELL: &str = "–";

/// IoU per class in table order, then mIoU, BIoU, AP, F1.
fn iou_row_values(m: &Metrics) -> Vec<Option<f64>> {
    let mut values: Vec<Option<f64>> = TABLE_CLASSES.iter().map(|&c| m.class(c).iou).collect();
    values.extend([m.miou, m.biou, m.ap, m.f1]);
    values
}

/// A fraction as a percentage with 2 decimals, or `–`.
fn format_percent(v: Option<f64>) -> String {
    v.map_or_else(|| NONE_CELL.to_string(), |v| format!("{:.2}", v * 100.0))
}

/// A change in fractions as signed percentage points with 2 decimals (`+0.12`, `-0.09`;
/// `0.00` when it rounds to zero), or `–`.
fn format_delta(d: Option<f64>) -> String {
    let Some(d) = d else {
        return NONE_CELL.to_string();
    };
    let pp = d * 100.0;
    let magnitude = format!("{:.2}", pp.abs());
    if magnitude == "0.00" {
        magnitude
    } else if pp > 0.0 {
        format!("+{magnitude}")
    } else {
        format!("-{magnitude}")
    }
}

fn titles(classes: &[Class]) -> String {
    classes
        .iter()
        .map(|c| c.title())
        .collect::<Vec<_>>()
        .join(", ")
}

/// A configuration name made safe for a table cell.
fn escape_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

fn table_row(cells: &[String]) -> String {
    format!("| {} |\n", cells.join(" | "))
}

/// Markdown separator: first column left-aligned, numbers right-aligned.
fn separator_row(columns: usize) -> String {
    let mut cells = vec!["---".to_string()];
    cells.extend(std::iter::repeat_n(
        "---:".to_string(),
        columns.saturating_sub(1),
    ));
    table_row(&cells)
}

fn class_names() -> Vec<String> {
    Class::ALL.iter().map(|c| c.name().to_string()).collect()
}

/// `report.json`'s top level.
#[derive(Serialize, Deserialize)]
struct ReportFile {
    version: u32,
    classes: Vec<String>,
    configurations: Vec<ConfigurationFile>,
}

#[derive(Serialize, Deserialize)]
struct ConfigurationFile {
    name: String,
    confusion: ConfusionMatrix,
    points: PointsFile,
    /// Derived from `confusion`: written for readers, ignored on reading.
    #[serde(default, skip_deserializing)]
    metrics: Option<Metrics>,
}

#[derive(Serialize, Deserialize)]
struct PointsFile {
    evaluated: u64,
    pred_unknown: u64,
    gt_unknown: u64,
    gt_unmatched: u64,
    pred_unmatched: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delta_formatting_is_signed_and_has_no_negative_zero() {
        assert_eq!(format_delta(Some(0.0012)), "+0.12");
        assert_eq!(format_delta(Some(-0.0009)), "-0.09");
        assert_eq!(format_delta(Some(-0.000_001)), "0.00");
        assert_eq!(format_delta(None), "–");
        assert_eq!(format_percent(Some(0.7368)), "73.68");
        assert_eq!(format_percent(Some(1.0)), "100.00");
    }

    #[test]
    fn separator_right_aligns_numbers() {
        assert_eq!(separator_row(3), "| --- | ---: | ---: |\n");
    }
}
