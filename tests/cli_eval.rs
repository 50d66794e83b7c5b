//! `bodyseg eval`: several named predictions, markdown output, report files, merging.

use crate::common::{
    assert_ok, bodyseg_line, refine_scene, stdout, succeeds_in, tempdir, words, write_scene,
};
use bodyseg_eval::Report;

#[test]
fn named_predictions_markdown_json_and_merge() {
    let dir = tempdir();
    let d = dir.path();
    write_scene(d);
    let out = refine_scene(d, &["--out", "refined.ply"]);
    assert_ok(&out, "bodyseg refine");

    // Markdown on stdout: the paper's table, one row per configuration and a change row.
    let out = bodyseg_line(
        d,
        "eval --pred Reference=in.ply --pred M-R-N=refined.ply --gt gt.ply",
    );
    assert_ok(&out, "bodyseg eval (markdown)");
    let md = stdout(&out);
    assert!(md.contains("| Reference |"), "{md}");
    assert!(md.contains("| M-R-N |"), "{md}");
    assert!(md.contains("Δ vs Reference"), "{md}");

    // JSON to a file; then merged with itself: counts double, metrics stay.
    let out = bodyseg_line(
        d,
        "eval --pred Reference=in.ply --pred M-R-N=refined.ply --gt gt.ply --format json --out report.json",
    );
    assert_ok(&out, "bodyseg eval --out report.json");
    assert_eq!(stdout(&out), "", "the report went to the file");
    let text = std::fs::read_to_string(d.join("report.json")).expect("report.json");
    let report = Report::from_json(&text).expect("a valid report");
    assert_eq!(report.names(), ["Reference", "M-R-N"]);

    let out = succeeds_in(
        d,
        &words("eval --merge report.json report.json --format json"),
    );
    let merged = Report::from_json(&stdout(&out)).expect("merged report");
    for (one, two) in report.configurations().iter().zip(merged.configurations()) {
        assert_eq!(two.evaluated(), 2 * one.evaluated());
        // Doubling every count keeps every ratio exactly (2a / 2b rounds as a / b).
        let (m1, m2) = (one.metrics(), two.metrics());
        assert_eq!(
            (m2.miou, m2.biou, m2.ap, m2.f1),
            (m1.miou, m1.biou, m1.ap, m1.f1)
        );
    }

    // --name names a single prediction.
    let out = succeeds_in(d, &words("eval --pred refined.ply --name mine --gt gt.ply"));
    assert!(stdout(&out).contains("| mine |"));
}
