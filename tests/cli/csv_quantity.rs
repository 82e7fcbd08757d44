//! A CSV file states that it holds a BRDF by a `# quantity: brdf` comment before its
//! header or by naming its value column `brdf`, as an ASTM file does with `MEAS_NAME BRDF`;
//! `--quantity` still decides over the file. The bundled CUReT file states it.

use crate::common;

use common::{data, goniofit, run_json};

/// A Lambertian BRDF fitted with absolute residuals and unit weights has the closed-form
/// optimum s = mean(y): the model is the constant s.
fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// The values of CUReT surface `group` in data/curet/curet.csv.
fn curet_values(group: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(data("curet/curet.csv")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f[0] == group)
        .map(|f| f[4].parse().unwrap())
        .collect()
}

fn lambert_fit(extra: &[&str], file: &std::path::Path) -> serde_json::Value {
    let mut args = vec!["fit", "--model", "lambert", "--no-intervals"];
    args.extend(extra);
    args.push(file.to_str().unwrap());
    let (code, v) = run_json(&args);
    assert_eq!(code, Some(0), "{v}");
    v
}

#[test]
fn the_bundled_curet_file_is_read_as_the_brdf_it_states() {
    let v = lambert_fit(&["--channel", "8"], &data("curet/curet.csv"));
    assert_eq!(v["setting"]["quantity"], "brdf");
    assert_eq!(v["setting"]["quantity_source"], "stated by the file");
    let s = v["params"]["scale"]["value"].as_f64().unwrap();
    let m = mean(&curet_values("8"));
    assert!((s / m - 1.0).abs() < 1e-9, "scale {s} vs mean BRDF {m}");
    // --quantity decides over the file.
    let v = lambert_fit(
        &["--channel", "8", "--quantity", "radiance"],
        &data("curet/curet.csv"),
    );
    assert_eq!(v["setting"]["quantity"], "radiance");
    assert_eq!(v["setting"]["quantity_source"], "--quantity");
}

#[test]
fn a_quantity_comment_or_a_brdf_column_reads_the_values_as_a_brdf() {
    let dir = tempfile::tempdir().unwrap();
    let rows = "30,10,0,0.5\n30,40,180,0.3\n60,20,90,0.2\n0,70,0,0.4\n";
    let stated = dir.path().join("stated.csv");
    std::fs::write(
        &stated,
        format!("# a scan\n# quantity: BRDF\ntheta_i,theta_r,phi_r,L\n{rows}"),
    )
    .unwrap();
    let column = dir.path().join("column.csv");
    std::fs::write(&column, format!("theta_i,theta_r,phi_r,brdf\n{rows}")).unwrap();
    let plain = dir.path().join("plain.csv");
    std::fs::write(&plain, format!("theta_i,theta_r,phi_r,L\n{rows}")).unwrap();
    let brdf_mean = mean(&[0.5, 0.3, 0.2, 0.4]);
    for file in [&stated, &column] {
        let v = lambert_fit(&[], file);
        assert_eq!(v["setting"]["quantity"], "brdf", "{}", file.display());
        assert_eq!(v["setting"]["quantity_source"], "stated by the file");
        let s = v["params"]["scale"]["value"].as_f64().unwrap();
        assert!((s / brdf_mean - 1.0).abs() < 1e-9, "{s}");
        // The same fit as --quantity brdf on the plain file.
        let same = lambert_fit(&["--quantity", "brdf"], &plain);
        assert_eq!(same["cost"], v["cost"]);
    }
    let v = lambert_fit(&[], &plain);
    assert_eq!(v["setting"]["quantity"], "radiance");
    assert_eq!(v["setting"]["quantity_source"], "default");
}

#[test]
fn a_quantity_comment_that_names_neither_brdf_nor_radiance_is_refused_with_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bad.csv");
    std::fs::write(
        &file,
        "# a scan\n# quantity: reflectance\ntheta_i,theta_r,phi_r,L\n30,10,0,0.5\n",
    )
    .unwrap();
    let out = goniofit()
        .args(["fit", "--model", "lambert"])
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains("bad.csv:2") && err.contains("reflectance"),
        "{err}"
    );
}
