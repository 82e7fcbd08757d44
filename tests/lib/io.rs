//! Readers and writers: CSV and ASTM E1392 parsing, conventions checked on the bundled
//! data, every bad-input case, atomic writes, and no panics on arbitrary input.

use crate::error::Error;
use crate::io::{self, read_bytes, read_dataset, write_atomic, Dataset, ReadOptions};
use proptest::prelude::*;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(p)
}

fn fit_opts() -> ReadOptions {
    ReadOptions {
        require_value: true,
        ..Default::default()
    }
}

fn csv(text: &str, opts: &ReadOptions) -> crate::error::Result<Dataset> {
    read_bytes(Path::new("t.csv"), text.as_bytes(), opts)
}

/// The (line, column, message) of an `Error::Input`, or a panic naming what came instead.
fn input_err(r: crate::error::Result<Dataset>) -> (usize, String, String) {
    match r {
        Err(Error::Input {
            path,
            line,
            column,
            message,
        }) => {
            assert!(!path.as_os_str().is_empty());
            (line, column, message)
        }
        other => panic!("expected Error::Input, got {other:?}"),
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

// ---------------------------------------------------------------- CSV: good input

#[test]
fn csv_basic_degrees_and_pass_through() {
    let ds = csv(
        "id,theta_i,theta_r,phi_r,L\na,30,45,0,1.5\nb,10,20,90,2\n",
        &fit_opts(),
    )
    .unwrap();
    assert_eq!(ds.headers, ["id", "theta_i", "theta_r", "phi_r", "L"]);
    assert_eq!(ds.rows[1], ["b", "10", "20", "90", "2"]);
    assert_eq!(ds.lines, [2, 3]);
    assert!(close(ds.samples[0].theta_i, 30f64.to_radians()));
    assert!(close(ds.samples[0].theta_r, 45f64.to_radians()));
    assert!(close(ds.samples[1].phi_r, PI / 2.0));
    assert_eq!(ds.value.as_deref(), Some(&[1.5, 2.0][..]));
    assert!(ds.weight.is_none() && ds.sigma_l.is_none() && ds.wavelength.is_none());
    assert!(ds.channel.is_none());
}

#[test]
fn csv_comments_blank_lines_crlf_bom_case_whitespace_quotes() {
    let text = "\u{feff}# a comment\r\n\r\n Theta_I , THETA_R,phi_r , Value ,note\r\n# another\r\n30, 45 ,0,1,\"x, y\"\r\n\r\n   \r\n40,40,10,2,z\r\n";
    let ds = csv(text, &fit_opts()).unwrap();
    assert_eq!(ds.len(), 2);
    assert_eq!(ds.headers[0], "Theta_I");
    assert_eq!(ds.lines, [5, 8]);
    assert_eq!(ds.rows[0][4], "x, y");
    assert_eq!(ds.value.as_deref(), Some(&[1.0, 2.0][..]));
}

#[test]
fn csv_radians() {
    let opts = ReadOptions {
        radians: true,
        ..fit_opts()
    };
    let ds = csv("theta_i,theta_r,phi_r,L\n0.5,1.5,-3,1\n", &opts).unwrap();
    assert_eq!(ds.samples[0].theta_i, 0.5);
    assert_eq!(ds.samples[0].theta_r, 1.5);
    assert_eq!(ds.samples[0].phi_r, -3.0);
    // 1.6 rad > π/2.
    let (line, col, msg) = input_err(csv("theta_i,theta_r,phi_r,L\n0.5,1.6,0,1\n", &opts));
    assert_eq!((line, col.as_str()), (2, "theta_r"));
    assert!(msg.contains("1.6"), "{msg}");
}

#[test]
fn csv_signed_theta_r() {
    let opts = ReadOptions {
        signed_theta_r: true,
        ..fit_opts()
    };
    let ds = csv("theta_i,theta_r,phi_r,L\n30,-20,0,1\n30,20,0,1\n", &opts).unwrap();
    assert!(close(ds.samples[0].theta_r, 20f64.to_radians()));
    assert!(close(ds.samples[0].phi_r, PI));
    assert_eq!(ds.samples[1].phi_r, 0.0);
    // In-plane data without a phi_r column.
    let ds = csv("theta_i,theta_r,L\n30,-20,1\n30,20,1\n", &opts).unwrap();
    assert!(close(ds.samples[0].phi_r, PI));
    assert_eq!(ds.samples[1].phi_r, 0.0);
    // Without signed mode a negative theta_r is an error that suggests the flag.
    let (line, col, msg) = input_err(csv("theta_i,theta_r,phi_r,L\n30,-20,0,1\n", &fit_opts()));
    assert_eq!((line, col.as_str()), (2, "theta_r"));
    assert!(
        msg.contains("-20") && msg.contains("--signed-theta-r"),
        "{msg}"
    );
}

#[test]
fn csv_column_mapping_weight_sigma_wavelength_group() {
    let opts = ReadOptions {
        columns: io::csv::parse_columns("theta_i=inc, theta_r=view,phi_r=az,L=brdf").unwrap(),
        ..fit_opts()
    };
    let ds = csv(
        "inc,view,az,brdf,sigma_L,wavelength,group\n10,20,30,1,0.5,0.55,red\n10,20,30,2,0.25,0.65,blue\n",
        &opts,
    )
    .unwrap();
    assert_eq!(ds.value.as_deref(), Some(&[1.0, 2.0][..]));
    assert_eq!(ds.sigma_l.as_deref(), Some(&[0.5, 0.25][..]));
    assert_eq!(ds.weight.as_deref(), Some(&[4.0, 16.0][..]));
    assert_eq!(ds.wavelength.as_deref(), Some(&[0.55, 0.65][..]));
    assert_eq!(ds.channel_names(), ["red", "blue"]);
    assert_eq!(ds.channel_indices("blue"), [1]);

    let ds = csv(
        "theta_i,theta_r,phi_r,L,weight\n10,20,30,1,3\n",
        &fit_opts(),
    )
    .unwrap();
    assert_eq!(ds.weight.as_deref(), Some(&[3.0][..]));
    assert!(ds.sigma_l.is_none());

    assert!(matches!(
        io::csv::parse_columns("speed=v"),
        Err(Error::Usage(_))
    ));
    assert!(matches!(
        io::csv::parse_columns("theta_i"),
        Err(Error::Usage(_))
    ));
}

#[test]
fn csv_value_optional_for_eval() {
    let ds = csv("theta_i,theta_r,phi_r\n10,20,30\n", &ReadOptions::default()).unwrap();
    assert!(ds.value.is_none());
    let (line, col, msg) = input_err(csv("theta_i,theta_r,phi_r\n10,20,30\n", &fit_opts()));
    assert_eq!((line, col.as_str()), (1, "L"));
    assert!(msg.contains("missing column L"), "{msg}");
}

// ---------------------------------------------------------------- CSV: bad input

/// Each bad file, the line and column the error must name, and a text it must show.
const BAD_CSV: &[(&str, usize, &str, &str)] = &[
    (
        "theta_i,theta_r,L\n10,20,1\n",
        1,
        "phi_r",
        "missing column phi_r",
    ),
    (
        "theta_r,phi_r,L\n10,20,1\n",
        1,
        "theta_i",
        "missing column theta_i",
    ),
    (
        "theta_i,phi_r,L\n10,20,1\n",
        1,
        "theta_r",
        "missing column theta_r",
    ),
    (
        "theta_i,theta_r,phi_r,L\n10,20,0,1\n10,abc,0,1\n",
        3,
        "theta_r",
        "'abc'",
    ),
    ("theta_i,theta_r,phi_r,L\n10,20,,1\n", 2, "phi_r", "empty"),
    ("theta_i,theta_r,phi_r,L\n10,20,0,NaN\n", 2, "L", "'NaN'"),
    ("theta_i,theta_r,phi_r,L\n10,20,0,inf\n", 2, "L", "'inf'"),
    (
        "theta_i,theta_r,phi_r,L\n10,20,1e999,1\n",
        2,
        "phi_r",
        "'1e999'",
    ),
    ("theta_i,theta_r,phi_r,L\n90,20,0,1\n", 2, "theta_i", "90"),
    ("theta_i,theta_r,phi_r,L\n-5,20,0,1\n", 2, "theta_i", "-5"),
    (
        "theta_i,theta_r,phi_r,L\n10,90.5,0,1\n",
        2,
        "theta_r",
        "90.5",
    ),
    ("theta_i,theta_r,phi_r,L\n10,-3,0,1\n", 2, "theta_r", "-3"),
    ("theta_i,theta_r,phi_r,L\n10,20,361,1\n", 2, "phi_r", "361"),
    (
        "theta_i,theta_r,phi_r,L\n10,20,-400,1\n",
        2,
        "phi_r",
        "-400",
    ),
    (
        "theta_i,theta_r,phi_r,L,weight\n10,20,0,1,0\n",
        2,
        "weight",
        "0",
    ),
    (
        "theta_i,theta_r,phi_r,L,weight\n10,20,0,1,-2\n",
        2,
        "weight",
        "-2",
    ),
    (
        "theta_i,theta_r,phi_r,L,sigma_L\n10,20,0,1,0\n",
        2,
        "sigma_L",
        "0",
    ),
    (
        "theta_i,theta_r,phi_r,L,sigma_L\n10,20,0,1,-0.1\n",
        2,
        "sigma_L",
        "-0.1",
    ),
    (
        "theta_i,theta_r,phi_r,L,wavelength\n10,20,0,1,0\n",
        2,
        "wavelength",
        "0",
    ),
    (
        "theta_i,theta_r,phi_r,L\n10,20,0,1\n10,20,0\n",
        3,
        "(row)",
        "3 fields",
    ),
    (
        "theta_i,theta_r,phi_r,L\n10,20,0,1,5\n",
        2,
        "(row)",
        "5 fields",
    ),
    (
        "theta_i,theta_r,phi_r,L\n10,20,0,0\n10,30,0,0\n",
        1,
        "L",
        "all 2 values are zero",
    ),
    (
        "theta_i,theta_r,phi_r,L,weight,sigma_L\n10,20,0,1,1,1\n",
        1,
        "sigma_L",
        "both",
    ),
    (
        "theta_i,theta_r,phi_r,L,value\n10,20,0,1,1\n",
        1,
        "value",
        "--columns L=NAME",
    ),
    (
        "# c\n\ntheta_i,theta_r,phi_r,L\n# c\n10,20,0,1\n\n10,x,0,1\n",
        7,
        "theta_r",
        "'x'",
    ),
];

#[test]
fn csv_bad_input_names_line_column_and_value() {
    for &(text, line, col, shows) in BAD_CSV {
        let (l, c, m) = input_err(csv(text, &fit_opts()));
        assert_eq!((l, c.as_str()), (line, col), "{text:?}: {m}");
        assert!(m.contains(shows), "{text:?}: message {m:?} lacks {shows:?}");
        // The displayed error names the file, the line and the column.
        let shown = Error::Input {
            path: "t.csv".into(),
            line: l,
            column: c.clone(),
            message: m,
        }
        .to_string();
        assert!(
            shown.starts_with(&format!("t.csv:{line}: column {col}:")),
            "{shown}"
        );
    }
}

#[test]
fn csv_empty_and_header_only_are_file_errors() {
    for text in ["", "\n\n", "# only a comment\n", "\u{feff}"] {
        match csv(text, &fit_opts()) {
            Err(Error::File { message, .. }) => assert!(message.contains("empty"), "{message}"),
            other => panic!("{text:?}: {other:?}"),
        }
    }
    match csv("theta_i,theta_r,phi_r,L\n# nothing\n\n", &fit_opts()) {
        Err(Error::File { message, .. }) => assert!(message.contains("no data rows"), "{message}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn csv_invalid_utf8_names_the_line() {
    let bytes = b"theta_i,theta_r,phi_r,L\n10,20,0,1\n10,2\xff,0,1\n";
    let (line, col, _) = input_err(read_bytes(Path::new("t.csv"), bytes, &fit_opts()));
    assert_eq!((line, col.as_str()), (3, "(text)"));
}

#[test]
fn csv_unknown_mapped_column() {
    let opts = ReadOptions {
        columns: vec![("theta_i".into(), "incidence".into())],
        ..fit_opts()
    };
    let (line, col, msg) = input_err(csv("theta_i,theta_r,phi_r,L\n10,20,0,1\n", &opts));
    assert_eq!((line, col.as_str()), (1, "incidence"));
    assert!(msg.contains("theta_i, theta_r"), "lists the header: {msg}");
}

#[test]
fn missing_file_is_io_error() {
    let r = read_dataset(Path::new("/nonexistent/x.csv"), &fit_opts());
    assert!(matches!(r, Err(Error::Io { .. })), "{r:?}");
}

// ---------------------------------------------------------------- ASTM

fn astm_opts(channel: Option<&str>) -> ReadOptions {
    ReadOptions {
        channel: channel.map(str::to_string),
        ..fit_opts()
    }
}

#[test]
fn astm_needs_a_channel_choice_and_lists_them() {
    let r = read_dataset(&data("cornell/garnet_red.astm"), &astm_opts(None));
    match r {
        Err(Error::Usage(m)) => {
            assert!(
                m.contains("31 channels") && m.contains("400nm") && m.contains("700nm"),
                "{m}"
            );
            assert!(m.contains("garnet_red.astm"), "{m}");
        }
        other => panic!("{other:?}"),
    }
    let r = read_dataset(&data("cornell/garnet_red.astm"), &astm_opts(Some("555nm")));
    assert!(
        matches!(r, Err(Error::Usage(ref m)) if m.contains("550nm")),
        "{r:?}"
    );
}

#[test]
fn astm_one_channel() {
    let ds = read_dataset(&data("cornell/garnet_red.astm"), &astm_opts(Some("550NM"))).unwrap();
    assert_eq!(ds.len(), 1439);
    assert_eq!(
        ds.headers,
        ["theta_i", "phi_i", "theta_s", "phi_s", "channel", "BRDF"]
    );
    assert!(ds.wavelength.as_ref().unwrap().iter().all(|&w| w == 550.0));
    assert!(ds.channel.as_ref().unwrap().iter().all(|c| c == "550nm"));
    // First data row (line 23): 0.872665,0.000000,0.573513,0.000000,...,550nm = 0.004352.
    assert_eq!(ds.lines[0], 23);
    assert_eq!(ds.value.as_ref().unwrap()[0], 0.004352);
    assert_eq!(ds.samples[0].theta_i, 0.872665);
    assert_eq!(ds.samples[0].theta_r, 0.573513);
    assert!(
        close(ds.samples[0].phi_r.abs(), PI),
        "phi_s = 0 is the back side"
    );
    assert_eq!(ds.rows[0][4..], ["550nm", "0.004352"]);
}

#[test]
fn astm_all_channels() {
    let ds = read_dataset(&data("cornell/krylon_blue.astm"), &astm_opts(Some("all"))).unwrap();
    assert_eq!(ds.len(), 1439 * 31);
    let names = ds.channel_names();
    assert_eq!(names.len(), 31);
    assert_eq!(names[0], "400nm");
    let wl = ds.wavelength.as_ref().unwrap();
    assert_eq!((wl[0], wl[30], wl[31]), (400.0, 700.0, 400.0));
    assert_eq!(ds.channel_indices("550nm").len(), 1439);
    assert_eq!(ds.lines[0], ds.lines[30]);
    assert_eq!(ds.samples[0], ds.samples[30]);
}

/// The azimuth convention, checked on the data: at every incidence angle the brightest
/// sample of the rough-paint lobe lies in the forward half-plane at φr ≈ 0 and θr near θi.
#[test]
fn astm_specular_peak_lands_at_phi_r_zero() {
    for file in ["cornell/garnet_red.astm", "cornell/krylon_blue.astm"] {
        let ds = read_dataset(&data(file), &astm_opts(Some("550nm"))).unwrap();
        let v = ds.value.as_ref().unwrap();
        let mut incidences: Vec<f64> = ds.samples.iter().map(|s| s.theta_i).collect();
        incidences.sort_by(f64::total_cmp);
        incidences.dedup();
        assert_eq!(incidences.len(), 8);
        for ti in incidences {
            let best = (0..ds.len())
                .filter(|&k| ds.samples[k].theta_i == ti)
                .max_by(|&a, &b| v[a].total_cmp(&v[b]))
                .unwrap();
            let s = ds.samples[best];
            assert!(
                s.phi_r.abs() < 1e-6,
                "{file} θi={ti}: peak at φr={}",
                s.phi_r
            );
            // θs is sampled on a 8°–10° grid; the rough lobe is skewed toward grazing.
            assert!(
                s.theta_r > ti - 0.15 && s.theta_r < ti + 0.35,
                "{file} θi={ti}: peak at θr={}",
                s.theta_r
            );
        }
    }
}

const ASTM_SMALL: &str = "LAB_NAME Test\nMEAS_NAME BRDF\nNUM_POINTS 3\nVARS theta_i,phi_i,theta_s,phi_s,550nm,650nm\n\n0.5,0,0.5,3.141593,1.0,2.0\n0.5,1.0,0.5,-2.141593,1.5,2.5\n0.5,0,0.3,0,0.1,0.2\n";

#[test]
fn astm_relative_azimuth_and_detection_by_content() {
    // No .astm extension: detected by the KEY value header and VARS.
    let ds = read_bytes(
        Path::new("x.txt"),
        ASTM_SMALL.as_bytes(),
        &astm_opts(Some("650nm")),
    )
    .unwrap();
    assert_eq!(ds.len(), 3);
    assert_eq!(ds.value.as_deref(), Some(&[2.0, 2.5, 0.2][..]));
    // φs − φi − π: row 1 → ~0, row 2 (φi = 1) → −2.141593 − 1 − π ≡ ~0, row 3 → π.
    assert!(ds.samples[0].phi_r.abs() < 1e-5);
    assert!(ds.samples[1].phi_r.abs() < 1e-5, "{}", ds.samples[1].phi_r);
    assert!(close(ds.samples[2].phi_r.abs(), PI));
    assert_eq!(ds.lines, [6, 7, 8]);
    // Whitespace-separated rows and CRLF work too.
    let ws = ASTM_SMALL
        .replace(',', " ")
        .replace(
            "VARS theta_i phi_i theta_s phi_s 550nm 650nm",
            "VARS theta_i,phi_i,theta_s,phi_s,550nm,650nm",
        )
        .replace('\n', "\r\n");
    let ds2 = read_bytes(
        Path::new("x.astm"),
        ws.as_bytes(),
        &astm_opts(Some("550nm")),
    )
    .unwrap();
    assert_eq!(ds2.value.as_deref(), Some(&[1.0, 1.5, 0.1][..]));
}

#[test]
fn astm_bad_input() {
    let opts = astm_opts(Some("550nm"));
    let rd = |t: &str| read_bytes(Path::new("x.astm"), t.as_bytes(), &opts);
    // A missing value.
    let (l, c, m) = input_err(rd(
        &ASTM_SMALL.replace("0.5,0,0.3,0,0.1,0.2", "0.5,0,0.3,0,,0.2")
    ));
    assert_eq!((l, c.as_str()), (8, "550nm"), "{m}");
    // A non-number.
    let (l, c, m) = input_err(rd(&ASTM_SMALL.replace("1.5,2.5", "abc,2.5")));
    assert_eq!((l, c.as_str()), (7, "550nm"));
    assert!(m.contains("'abc'"));
    // θs beyond 90° (radians).
    let (l, c, m) = input_err(rd(&ASTM_SMALL.replace("0.5,0,0.3,0", "0.5,0,1.7,0")));
    assert_eq!((l, c.as_str()), (8, "theta_s"));
    assert!(m.contains("1.7") && m.contains("radians"), "{m}");
    // Ragged row.
    let (l, c, _) = input_err(rd(&ASTM_SMALL.replace(",0.1,0.2", ",0.1")));
    assert_eq!((l, c.as_str()), (8, "(row)"));
    // Truncated file.
    let r = rd(&ASTM_SMALL.replace("0.5,0,0.3,0,0.1,0.2\n", ""));
    assert!(
        matches!(r, Err(Error::File { ref message, .. }) if message.contains("NUM_POINTS")),
        "{r:?}"
    );
    // No VARS, no rows, missing angle column.
    assert!(matches!(
        rd("LAB_NAME x\nNUM_POINTS 0\n"),
        Err(Error::File { .. })
    ));
    assert!(matches!(
        rd("LAB_NAME x\nVARS theta_i,phi_i,theta_s,phi_s,550nm\n"),
        Err(Error::File { .. })
    ));
    let (l, c, _) = input_err(rd(
        "LAB_NAME x\nVARS theta_i,phi_i,theta_s,550nm\n0,0,0,1\n",
    ));
    assert_eq!((l, c.as_str()), (2, "phi_s"));
    // Data before VARS.
    let (l, _, _) = input_err(rd("LAB_NAME x\n0,0,0,0,1\n"));
    assert_eq!(l, 2);
    // All zero with require_value.
    let zeros = "VARS theta_i,phi_i,theta_s,phi_s,550nm\n0.1,0,0.1,3.14,0\n";
    assert!(matches!(rd(zeros), Err(Error::File { .. })));
    let eval_opts = ReadOptions {
        require_value: false,
        ..opts.clone()
    };
    assert!(read_bytes(Path::new("x.astm"), zeros.as_bytes(), &eval_opts).is_ok());
}

// ---------------------------------------------------------------- NIST PTFE

#[test]
fn nist_ptfe_layout_is_detected() {
    let ds = read_dataset(&data("nist-ptfe/PTFE.data.csv"), &fit_opts()).unwrap();
    assert_eq!(ds.len(), 7296);
    assert_eq!(ds.headers.len(), 21);
    assert_eq!(ds.headers[5], "f_r11");
    let wl = ds.wavelength.as_ref().unwrap();
    let mut lams = wl.clone();
    lams.sort_by(f64::total_cmp);
    lams.dedup();
    assert_eq!(
        lams,
        [0.351, 0.532, 0.633, 1.064],
        "µm, from the lambda column"
    );
    // First row: thetai = −0.001 (source at azimuth 180°), thetar 80.0258, phir −156.038.
    let s = ds.samples[0];
    assert!(close(s.theta_i, 0.001f64.to_radians()));
    assert!(close(s.theta_r, 80.0258f64.to_radians()));
    assert!(close(s.phi_r, (-156.038f64).to_radians()));
    assert_eq!(ds.value.as_ref().unwrap()[0], 0.262);
    // Forward scatter at θi = 75°, 633 nm: the φr ≈ 0 side is brighter than φr ≈ 180°.
    let v = ds.value.as_ref().unwrap();
    let mean = |fwd: bool| {
        let sel: Vec<f64> = (0..ds.len())
            .filter(|&k| {
                let s = ds.samples[k];
                wl[k] == 0.633
                    && close(s.theta_i, 75f64.to_radians())
                    && (40f64.to_radians()..70f64.to_radians()).contains(&s.theta_r)
                    && if fwd {
                        s.phi_r.abs() < 30f64.to_radians()
                    } else {
                        s.phi_r.abs() > 150f64.to_radians()
                    }
            })
            .map(|k| v[k])
            .collect();
        assert!(sel.len() >= 3);
        sel.iter().sum::<f64>() / sel.len() as f64
    };
    assert!(
        mean(true) > 1.2 * mean(false),
        "{} vs {}",
        mean(true),
        mean(false)
    );
}

#[test]
fn nist_layout_random_file_convention() {
    // Germer's random file: positive thetai with source azimuth phi; mirror at phi + 180.
    let text = "lambda,thetai,phi,thetar,phir,f_r11\n0.532,40,30,40,210,1\n0.532,40,30,40,30,1\n";
    let ds = csv(text, &fit_opts()).unwrap();
    assert!(ds.samples[0].phi_r.abs() < 1e-12);
    assert!(close(ds.samples[1].phi_r.abs(), PI));
}

// ---------------------------------------------------------------- writing

#[test]
fn write_atomic_writes_and_cleans_up() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("out.csv");
    write_atomic(&p, |w| w.write_all(b"hello\n")).unwrap();
    assert_eq!(std::fs::read_to_string(&p).unwrap(), "hello\n");

    // A failing writer leaves the old file intact and no temporary behind.
    let r = write_atomic(&p, |w| {
        w.write_all(b"partial")?;
        Err(std::io::Error::other("boom"))
    });
    assert!(matches!(r, Err(Error::Write { .. })));
    assert_eq!(std::fs::read_to_string(&p).unwrap(), "hello\n");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);

    // A missing directory: an error, and nothing created.
    let q = dir.path().join("missing").join("out.csv");
    let r = write_atomic(&q, |w| w.write_all(b"x"));
    match r {
        Err(Error::File { path, message }) => {
            assert_eq!(path, q);
            assert!(
                message.contains("missing") && message.contains("no such directory"),
                "{message}"
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(!dir.path().join("missing").exists());
}

#[test]
fn write_csv_quotes_and_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.csv");
    let headers = vec![
        "id".to_string(),
        "theta_i".into(),
        "theta_r".into(),
        "phi_r".into(),
    ];
    let rows = vec![vec![
        "a, b".to_string(),
        "10".into(),
        "20".into(),
        "0".into(),
    ]];
    io::write_csv(&p, &headers, &rows).unwrap();
    let ds = read_dataset(&p, &ReadOptions::default()).unwrap();
    assert_eq!(ds.headers, headers);
    assert_eq!(ds.rows, rows);
}

#[test]
fn format_value_round_trips() {
    for v in [
        0.1,
        1.0 / 3.0,
        1e-300,
        6.02214076e23,
        0.0,
        -2.5e-7,
        f64::MIN_POSITIVE,
    ] {
        let s = io::format_value(v);
        assert_eq!(s.parse::<f64>().unwrap(), v, "{s}");
    }
}

#[test]
fn channel_wavelengths() {
    use io::wavelength_nm_of_channel as w;
    assert_eq!(w("550nm"), Some(550.0));
    assert_eq!(w(" 550 NM "), Some(550.0));
    assert_eq!(w("0.55um"), Some(550.0));
    assert_eq!(w("633"), Some(633.0));
    assert_eq!(w("BRDF"), None);
    assert_eq!(w("-5nm"), None);
}

// ---------------------------------------------------------------- no panics

const VALID_CSV: &str = "# comment\nid,theta_i,theta_r,phi_r,L,sigma_L,wavelength,group\na,10,20,0,1.5,0.1,0.5,x\nb,30,-30,180,2.5,0.2,0.6,y\n\"c\",45,45,0,1e-3,1,0.7,z\n";

fn read_all_ways(name: &str, bytes: &[u8]) {
    for opts in [
        fit_opts(),
        ReadOptions::default(),
        ReadOptions {
            radians: true,
            signed_theta_r: true,
            channel: Some("all".into()),
            ..fit_opts()
        },
        ReadOptions {
            channel: Some("550nm".into()),
            columns: vec![("L".into(), "550nm".into())],
            ..Default::default()
        },
    ] {
        if let Ok(ds) = read_bytes(Path::new(name), bytes, &opts) {
            // Whatever is accepted is consistent and valid.
            assert!(!ds.is_empty());
            assert_eq!(ds.rows.len(), ds.len());
            assert_eq!(ds.lines.len(), ds.len());
            for r in &ds.rows {
                assert_eq!(r.len(), ds.headers.len());
            }
            for s in &ds.samples {
                s.validate().unwrap();
            }
            for v in [&ds.value, &ds.weight, &ds.sigma_l, &ds.wavelength]
                .into_iter()
                .flatten()
            {
                assert_eq!(v.len(), ds.len());
                assert!(v.iter().all(|x| x.is_finite()));
            }
        }
    }
}

/// Mutate a valid file: replace, insert or delete bytes at chosen places.
fn mutate(base: &str, edits: &[(usize, u8, u8)]) -> Vec<u8> {
    let mut b = base.as_bytes().to_vec();
    for &(pos, kind, byte) in edits {
        if b.is_empty() {
            b.push(byte);
            continue;
        }
        let i = pos % b.len();
        match kind % 3 {
            0 => b[i] = byte,
            1 => b.insert(i, byte),
            _ => {
                b.remove(i);
            }
        }
    }
    b
}

fn edge_number() -> impl Strategy<Value = String> {
    prop_oneof![
        (-400.0f64..400.0).prop_map(|v| v.to_string()),
        (-2.0f64..2.0).prop_map(|v| v.to_string()),
        Just("90".to_string()),
        Just("89.99999999999999999".to_string()),
        Just("1.5707963267948966".to_string()),
        Just("-0".to_string()),
        Just("0".to_string()),
        Just("1e-320".to_string()),
        Just("1e999".to_string()),
        Just("nan".to_string()),
        Just("".to_string()),
        Just("360".to_string()),
        Just("-360.0000001".to_string()),
    ]
}

fn interesting_byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        Just(b','),
        Just(b'\n'),
        Just(b'\r'),
        Just(b'"'),
        Just(b'#'),
        Just(b'-'),
        Just(b'.'),
        Just(b'e'),
        Just(b' '),
        Just(b'9'),
        Just(b'0'),
        any::<u8>(),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        read_all_ways("p.csv", &bytes);
        read_all_ways("p.astm", &bytes);
    }

    #[test]
    fn arbitrary_text_never_panics(text in "[a-zA-Z_0-9,.#\\- \r\n\"eE]{0,300}") {
        read_all_ways("p.csv", text.as_bytes());
        read_all_ways("p.astm", text.as_bytes());
        let astm = format!("VARS theta_i,phi_i,theta_s,phi_s,550nm\n{text}");
        read_all_ways("p.astm", astm.as_bytes());
    }

    #[test]
    fn arbitrary_unicode_never_panics(text in "\\PC{0,200}", sep in "[,\n\"# ]") {
        let text = text.replace('x', &sep);
        read_all_ways("u.csv", text.as_bytes());
        read_all_ways("u.astm", text.as_bytes());
        let csv = format!("theta_i,theta_r,phi_r,L\n{text}");
        read_all_ways("u.csv", csv.as_bytes());
    }

    #[test]
    fn structured_csv_with_edge_numbers(
        rows in proptest::collection::vec(proptest::collection::vec(edge_number(), 7), 1..5)
    ) {
        let mut text = String::from("theta_i,theta_r,phi_r,L,sigma_L,wavelength,group\n");
        for r in &rows {
            text.push_str(&r.join(","));
            text.push('\n');
        }
        read_all_ways("s.csv", text.as_bytes());
        let astm = format!("NUM_POINTS {}\nVARS theta_i,phi_i,theta_s,phi_s,550nm,1um,x\n{}", rows.len(), &text[text.find('\n').unwrap() + 1..]);
        read_all_ways("s.astm", astm.as_bytes());
    }

    #[test]
    fn mutated_valid_csv_never_panics(
        edits in proptest::collection::vec((any::<usize>(), any::<u8>(), interesting_byte()), 1..8)
    ) {
        read_all_ways("m.csv", &mutate(VALID_CSV, &edits));
    }

    #[test]
    fn mutated_valid_astm_never_panics(
        edits in proptest::collection::vec((any::<usize>(), any::<u8>(), interesting_byte()), 1..8)
    ) {
        read_all_ways("m.astm", &mutate(ASTM_SMALL, &edits));
        read_all_ways("m.txt", &mutate(ASTM_SMALL, &edits));
    }

    #[test]
    fn valid_angles_are_accepted(
        ti in 0.0f64..89.999, tr in -90.0f64..=90.0, pr in -360.0f64..=360.0
    ) {
        let opts = ReadOptions { signed_theta_r: true, ..fit_opts() };
        let text = format!("theta_i,theta_r,phi_r,L\n{ti},{tr},{pr},1\n");
        let ds = csv(&text, &opts).unwrap();
        ds.samples[0].validate().unwrap();
        prop_assert!((ds.samples[0].theta_r - tr.abs().to_radians()).abs() < 1e-12);
    }
}

#[test]
fn csv_quoted_line_breaks_keep_line_numbers() {
    let text = "id,theta_i,theta_r,phi_r,L\n\"two\nlines\",10,20,0,1\n\"q\"\"uote\",10,x,0,1\n";
    let (line, col, _) = input_err(csv(text, &fit_opts()));
    assert_eq!((line, col.as_str()), (4, "theta_r"));
    let ok = csv(&text.replace(",x,", ",20,"), &fit_opts()).unwrap();
    assert_eq!(ok.rows[0][0], "two\nlines");
    assert_eq!(ok.rows[1][0], "q\"uote");
    assert_eq!(ok.lines, [2, 4]);
    let (line, _, m) = input_err(csv("theta_i,theta_r,phi_r,L\n10,20,0,\"1\n", &fit_opts()));
    assert_eq!(line, 2);
    assert!(m.contains("never closed"), "{m}");
    let (line, _, m) = input_err(csv(
        "theta_i,theta_r,phi_r,L\n10,20,0,\"1\"x\n",
        &fit_opts(),
    ));
    assert_eq!(line, 2);
    assert!(m.contains("after a closing quote"), "{m}");
}

#[cfg(unix)]
#[test]
fn write_atomic_gives_ordinary_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("out.csv");
    write_atomic(&p, |w| w.write_all(b"x")).unwrap();
    let mode = std::fs::metadata(&p).unwrap().permissions().mode();
    // The same mode as a file created the ordinary way (0o666 less the umask).
    let q = dir.path().join("plain.csv");
    std::fs::write(&q, b"x").unwrap();
    let plain = std::fs::metadata(&q).unwrap().permissions().mode();
    assert_eq!(mode & 0o777, plain & 0o777);
}

#[test]
fn dataset_subset_by_channel() {
    let ds = read_dataset(&data("cornell/garnet_red.astm"), &astm_opts(Some("all"))).unwrap();
    let idx = ds.channel_indices("700nm");
    let sub = ds.subset(&idx);
    assert_eq!(sub.len(), 1439);
    assert!(sub.wavelength.as_ref().unwrap().iter().all(|&w| w == 700.0));
    assert_eq!(sub.rows[0][4], "700nm");
    assert_eq!(sub.lines[0], 23);
    assert_eq!(sub.value.as_ref().unwrap()[0], 0.050083);
}

fn csv_row() -> impl Strategy<Value = Vec<String>> {
    proptest::collection::vec("[a-z0-9 ,\"#\r\n\t.-]{0,6}", 1..5)
}

proptest! {
    /// What write_csv writes, the CSV reader splits back into exactly the same fields.
    #[test]
    fn written_csv_reads_back_exactly(rows in proptest::collection::vec(csv_row(), 1..6)) {
        let rows: Vec<Vec<String>> = rows
            .into_iter()
            .filter(|r| r.iter().any(|f| !f.is_empty()))
            .collect();
        let mut buf = Vec::new();
        for r in &rows {
            io::write_record(&mut buf, r).unwrap();
        }
        let text = String::from_utf8(buf).unwrap();
        let back = io::csv::split_records(&text).unwrap();
        let fields: Vec<Vec<String>> = back.into_iter().map(|(_, f)| f).collect();
        prop_assert_eq!(fields, rows);
    }
}

// ---------------------------------------------------------------- hostile structure

#[test]
fn astm_duplicate_channels_and_conflicting_num_points_are_refused() {
    let rd =
        |t: &str, ch: &str| read_bytes(Path::new("x.astm"), t.as_bytes(), &astm_opts(Some(ch)));
    // Two columns named 550nm (any case): `--channel all` would merge them under one scale.
    let dup = ASTM_SMALL.replace("550nm,650nm", "550nm,550NM");
    assert_ne!(dup, ASTM_SMALL);
    for ch in ["all", "550nm"] {
        let (l, c, m) = input_err(rd(&dup, ch));
        assert_eq!((l, c.as_str()), (4, "550NM"), "{m}");
        assert!(m.contains("twice (columns 5 and 6)"), "{m}");
    }
    // Two NUM_POINTS lines that disagree; the same count twice is harmless.
    let two = ASTM_SMALL.replace("NUM_POINTS 3\n", "NUM_POINTS 3\nNUM_POINTS 4\n");
    assert_ne!(two, ASTM_SMALL);
    let (l, c, m) = input_err(rd(&two, "550nm"));
    assert_eq!((l, c.as_str()), (4, "NUM_POINTS"), "{m}");
    assert!(m.contains("'4'") && m.contains("line 3 said '3'"), "{m}");
    let same = ASTM_SMALL.replace("NUM_POINTS 3\n", "NUM_POINTS 3\nNUM_POINTS 3\n");
    assert_eq!(rd(&same, "550nm").unwrap().len(), 3);
}

#[test]
fn a_row_of_too_many_fields_is_cut_off_while_it_is_read() {
    // 200 000 fields on one line (1.2 MB): refused by the limit, naming the line.
    let wide = format!("theta_i,theta_r,phi_r,L\n{}1.5\n", "1.5,".repeat(199_999));
    let err = io::csv::split_records_limited(&wide, 16).unwrap_err();
    assert_eq!(err.0, 2);
    assert_eq!(err.1, "row has 200000 fields, the header on line 1 has 4");
    // A header past the limit.
    let err = io::csv::split_records_limited(&"h,".repeat(100), 16).unwrap_err();
    assert_eq!(
        err,
        (
            1,
            "the header has more than 16 fields (a measurement table has a few columns)"
                .to_string()
        )
    );
    // Through the reader (default limit): the same message, an Error::Input on line 2.
    let (l, c, m) = input_err(csv(&wide, &fit_opts()));
    assert_eq!((l, c.as_str()), (2, "(row)"));
    assert_eq!(m, "row has 200000 fields, the header on line 1 has 4");
    let header = format!("{}L\n1\n", "x,".repeat(io::csv::MAX_FIELDS));
    let (l, _, m) = input_err(csv(&header, &fit_opts()));
    assert_eq!(l, 1);
    assert!(
        m.contains(&format!("more than {} fields", io::csv::MAX_FIELDS)),
        "{m}"
    );
    // ASTM: a data row past the VARS count.
    let astm = ASTM_SMALL.replace("0.5,0,0.3,0,0.1,0.2", &"0.5,".repeat(100_000));
    let (l, c, m) = input_err(read_bytes(
        Path::new("x.astm"),
        astm.as_bytes(),
        &astm_opts(Some("550nm")),
    ));
    assert_eq!((l, c.as_str()), (8, "(row)"));
    assert!(
        m.starts_with("row has more than 6 fields, VARS (line 4) names 6"),
        "{m}"
    );
}

#[test]
fn other_delimiters_are_named() {
    let msg = |t: &str| input_err(csv(t, &fit_opts())).2;
    let m = msg("theta_i;theta_r;phi_r;L\n30;20;0;1\n");
    assert!(
        m.contains("separated by ';'") && !m.contains("decimal commas"),
        "{m}"
    );
    let m = msg("theta_i;theta_r;phi_r;L\n30,5;20;0;1,25\n");
    assert!(m.contains("separated by ';' with decimal commas"), "{m}");
    let m = msg("theta_i\ttheta_r\tphi_r\tL\n30\t20\t0\t1\n");
    assert!(m.contains("separated by 'tab'"), "{m}");
    let m = msg("theta_i,theta_r,phi_r,L\n30,5,20,0,1,25\n");
    assert!(m.contains("decimal commas?"), "{m}");
    // A comma file with a ragged row of integers is not called decimal commas... unless
    // digits touch a comma, which is all the hint can see: it is phrased as a question.
    let m = msg("theta_i,theta_r,phi_r,L\n30,20,0\n");
    assert!(
        m.contains("row has 3 fields") && !m.contains("decimal"),
        "{m}"
    );
    // ASTM VARS separated by semicolons.
    let r = read_bytes(
        Path::new("x.astm"),
        b"VARS theta_i;phi_i;theta_s;phi_s;550nm\n0;0;0;0;1\n",
        &astm_opts(None),
    );
    let (_, _, m) = input_err(r);
    assert!(m.contains("separated by ';'"), "{m}");
}

#[test]
fn hostile_names_are_escaped_in_messages() {
    let name = "a\nfake: line\u{202e}lmth.exe";
    let r = read_bytes(
        Path::new(name),
        b"theta_i,theta_r,phi_r\n100,0,0\n",
        &ReadOptions::default(),
    );
    let text = r.unwrap_err().to_string();
    assert_eq!(
        text,
        "a\\nfake: line\\u{202e}lmth.exe:2: column theta_i: theta_i = 100° is outside [0, 90°)"
    );
    assert_eq!(io::shown_text("550nm"), "550nm");
    assert_eq!(
        io::shown_text("x\u{2066}\ty\r\u{1b}"),
        "x\\u{2066}\\ty\\r\\u{1b}"
    );
    // A hostile column name in the header.
    let r = read_bytes(
        Path::new("t.csv"),
        "theta_i,theta_r,phi_r,L\u{202e}\n10,0,0,abc\n".as_bytes(),
        &ReadOptions {
            columns: vec![("L".into(), "L\u{202e}".into())],
            ..fit_opts()
        },
    );
    let text = r.unwrap_err().to_string();
    assert!(
        text.contains("column L\\u{202e}:") && !text.contains('\u{202e}'),
        "{text}"
    );
}
