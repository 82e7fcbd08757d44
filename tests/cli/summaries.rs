//! What the reports of many fits say about the fits that are not usable: a batch's
//! `[[Summary]]`, `--summary` CSV, JSON and closing line count what did not converge and
//! give each row's termination; `--model auto` marks candidates that ended degenerate or
//! did not converge in its text, JSON and HTML comparison, and names a tie (ΔBIC < 2).

use crate::common;

use common::{data, goniofit, run_json};
use std::path::Path;

/// An exactly Lambertian radiance L = sign · 0.2 cos θi at the angles of the bundled
/// in-plane scan: `(theta_i, theta_r, phi_r, L)` rows.
fn lambertian(sign: f64) -> Vec<[f64; 4]> {
    let text = std::fs::read_to_string(data("synthetic/lambert_specular.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2], sign * 0.2 * v[0].to_radians().cos()]
        })
        .collect()
}

/// ½ Σ L²: the cost of every model whose amplitudes are all 0 (absolute residuals).
fn half_sum_of_squares(rows: &[[f64; 4]]) -> f64 {
    0.5 * rows.iter().map(|r| r[3] * r[3]).sum::<f64>()
}

fn write_rows(path: &Path, rows: &[[f64; 4]], group: Option<&[&str]>) {
    let mut text = String::from("theta_i,theta_r,phi_r,L");
    text += if group.is_some() { ",group\n" } else { "\n" };
    for (k, r) in rows.iter().enumerate() {
        text += &format!("{},{},{},{}", r[0], r[1], r[2], r[3]);
        if let Some(g) = group {
            text += &format!(",{}", g[k]);
        }
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

/// Two groups: `pos` exactly Lambertian, `neg` its negative. A Lambertian scale s ≥ 0 fits
/// `neg` best at s = 0 (every residual −L > 0 grows with s), the edge of its domain: that
/// fit is degenerate by construction, the other converges.
fn positive_and_negative(dir: &Path) -> (std::path::PathBuf, f64) {
    let pos = lambertian(1.0);
    let neg = lambertian(-1.0);
    let mut rows = pos.clone();
    rows.extend(&neg);
    let groups: Vec<&str> = pos
        .iter()
        .map(|_| "pos")
        .chain(neg.iter().map(|_| "neg"))
        .collect();
    let file = dir.join("pos_neg.csv");
    write_rows(&file, &rows, Some(&groups));
    (file, half_sum_of_squares(&neg))
}

#[test]
fn a_batch_counts_the_fits_that_did_not_converge_and_gives_each_termination() {
    let dir = tempfile::tempdir().unwrap();
    let (file, neg_cost) = positive_and_negative(dir.path());
    let summary = dir.path().join("fits.csv");
    let out = goniofit()
        .args([
            "fit",
            "--model",
            "lambert",
            "--by-group",
            "--no-intervals",
            "--summary",
        ])
        .arg(&summary)
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3), "one fit did not converge");
    let text = String::from_utf8(out.stdout).unwrap();
    let table = text.split("[[Summary]]").nth(1).expect("a summary table");
    assert!(
        table.starts_with(" (2 fits, 1 did not converge (degenerate 1);"),
        "{table}"
    );
    let neg = table.lines().find(|l| l.contains("[neg]")).unwrap();
    assert!(
        neg.contains(" NO ") && neg.contains(" degenerate "),
        "{neg}"
    );
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(
        stderr.contains("fitted 2 datasets")
            && stderr.contains("; 1 did not converge (degenerate 1)"),
        "{stderr}"
    );
    // The CSV names the termination per row; the degenerate fit sits at s = 0: cost ½ΣL².
    let csv = std::fs::read_to_string(&summary).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let neg_row = rows.iter().find(|r| r[0].ends_with("[neg]")).unwrap();
    let pos_row = rows.iter().find(|r| r[0].ends_with("[pos]")).unwrap();
    assert_eq!(neg_row[col("termination")], "degenerate");
    assert_eq!(neg_row[col("converged")], "false");
    assert_eq!(pos_row[col("converged")], "true");
    let cost: f64 = neg_row[col("cost")].parse().unwrap();
    assert!((cost / neg_cost - 1.0).abs() < 1e-9, "{cost} vs {neg_cost}");
    // JSON: the count beside the rows.
    let (_, v) = run_json(&[
        "fit".as_ref(),
        "--model".as_ref(),
        "lambert".as_ref(),
        "--by-group".as_ref(),
        "--no-intervals".as_ref(),
        file.as_os_str(),
    ]);
    assert_eq!(v["not_converged"], 1);
    assert_eq!(v["datasets"], 2);
}

#[test]
fn auto_marks_every_candidate_that_is_not_usable_in_text_json_and_html() {
    // Negative Lambertian data: every model's amplitudes end at 0 (all values lie below
    // any model value ≥ 0), so every candidate is degenerate at cost ½ΣL².
    let dir = tempfile::tempdir().unwrap();
    let rows = lambertian(-1.0);
    let file = dir.path().join("neg.csv");
    write_rows(&file, &rows, None);
    let html = dir.path().join("report.html");
    let out = goniofit()
        .args([
            "fit",
            "--model",
            "auto",
            "--wavelength",
            "1",
            "--no-intervals",
            "--html",
        ])
        .arg(&html)
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let text = String::from_utf8(out.stdout).unwrap();
    let table = text.split("[[goniofit").next().unwrap();
    for model in [
        "lambert ",
        "lambert-specular",
        "kbs ",
        "kbs+lambert ",
        "kbs+lambert --fresnel dielectric --shadowing smith",
    ] {
        let line = table
            .lines()
            .find(|l| l.trim_start().starts_with(model))
            .unwrap_or_else(|| panic!("{model}: {table}"));
        assert!(line.contains("degenerate (not usable)"), "{line}");
    }
    let page = std::fs::read_to_string(&html).unwrap();
    let section = page.split("<h2>Model comparison</h2>").nth(1).unwrap();
    let section = section.split("</table>").next().unwrap();
    assert_eq!(
        section.matches("degenerate (not usable)").count(),
        5,
        "{section}"
    );
    let (_, v) = run_json(&[
        "fit".as_ref(),
        "--model".as_ref(),
        "auto".as_ref(),
        "--wavelength".as_ref(),
        "1".as_ref(),
        "--no-intervals".as_ref(),
        file.as_os_str(),
    ]);
    let expected = half_sum_of_squares(&rows);
    for c in v["comparison"].as_array().unwrap() {
        assert_eq!(c["termination"], "degenerate", "{c}");
        assert_eq!(c["converged"], false);
        let cost = c["cost"].as_f64().unwrap();
        assert!((cost / expected - 1.0).abs() < 1e-6, "{c}");
    }
}

#[test]
fn auto_marks_ties_by_delta_bic_and_names_them_in_a_note() {
    // CUReT surfaces 7 and 30 (BRDFs, as the file states): every usable candidate within
    // ΔBIC < 2 of the chosen one is a tie, and only those; a tie is named in a note, and
    // without one no note speaks of a tie.
    for channel in ["7", "30"] {
        let (_, v) = run_json(&[
            "fit",
            "--model",
            "auto",
            "--wavelength",
            "550nm",
            "--channel",
            channel,
            "--no-intervals",
            data("curet/curet.csv").to_str().unwrap(),
        ]);
        check_ties(&v);
    }
}

/// The comparison's ties are the usable candidates within ΔBIC < 2 of the chosen one, and
/// the notes name them as `tied_with`'s note does.
fn check_ties(v: &serde_json::Value) {
    let cmp = v["comparison"].as_array().unwrap();
    let chosen = cmp.iter().find(|c| c["chosen"] == true).unwrap();
    let best = chosen["bic"].as_f64().unwrap();
    let mut tied = Vec::new();
    for c in cmp {
        let d = c["bic"].as_f64().unwrap() - best;
        assert!((c["delta_bic"].as_f64().unwrap() - d).abs() < 1e-9, "{c}");
        let expect = c["chosen"] == false && c["converged"] == true && d < 2.0;
        assert_eq!(c["tie"], expect, "{c}");
        if expect {
            tied.push((c["model"].as_str().unwrap().to_string(), d));
        }
    }
    let notes: Vec<&str> = v["notes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    let a = chosen["model"].as_str().unwrap();
    match &tied[..] {
        [] => assert!(!notes.iter().any(|n| n.starts_with("tie:")), "{notes:?}"),
        [(b, d)] => {
            let note =
                format!("tie: {a} and {b} differ by ΔBIC = {d:.2} < 2; the data do not prefer one");
            assert!(notes.contains(&note.as_str()), "{note} not in {notes:?}");
        }
        _ => assert!(
            notes
                .iter()
                .any(|n| n.starts_with(&format!("tie: {a} and "))),
            "{notes:?}"
        ),
    }
}

#[test]
fn summary_to_standard_output_replaces_the_text_reports() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("groups.csv");
    let rows = lambertian(1.0);
    let labels: Vec<&str> = (0..rows.len()).map(|i| ["a", "b"][i % 2]).collect();
    write_rows(&path, &rows, Some(&labels));
    let fit = |extra: &[&str]| {
        goniofit()
            .args(["fit", "--model", "lambert", "--by-group", "--quiet"])
            .args(extra)
            .arg(&path)
            .output()
            .unwrap()
    };
    let out = fit(&["--summary", "-"]);
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(lines[0].starts_with("group,n,converged,"), "{text}");
    assert!(lines[1].contains("[a]") && lines[2].contains("[b]"));
    // The same rows as a --summary file beside the text reports.
    let file = dir.path().join("s.csv");
    let beside = fit(&["--summary", file.to_str().unwrap()]);
    assert!(String::from_utf8(beside.stdout)
        .unwrap()
        .contains("[[goniofit"));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), text);
    // With --warm-start (each group started at the one before it) too: the rows alone
    // are those written beside the reports.
    let warm = fit(&["--summary", "-", "--warm-start"]);
    let beside = fit(&["--summary", file.to_str().unwrap(), "--warm-start"]);
    assert!(warm.status.success() && beside.status.success());
    let warm = String::from_utf8(warm.stdout).unwrap();
    assert_eq!(std::fs::read_to_string(&file).unwrap(), warm);
    assert_eq!(warm.lines().count(), 3, "{warm}");
    let both = fit(&["--summary", "-", "--json"]);
    assert_eq!(both.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&both.stderr).contains("--summary -"));
}
