//! The batch outputs of `goniofit fit`: one HTML page for several fits (summary table,
//! overview, one section per fit) and one `--plot` folder per fit; and the single page's
//! words for a parameter without an interval.

use crate::common;

use common::data;
use predicates::str::contains;

/// The text between the first `open` after `from` and the next `close`.
fn between<'a>(s: &'a str, open: &str, close: &str) -> &'a str {
    let i = s.find(open).unwrap_or_else(|| panic!("no {open}")) + open.len();
    let j = s[i..].find(close).unwrap_or_else(|| panic!("no {close}")) + i;
    &s[i..j]
}

/// The text content of an HTML fragment (tags dropped, the page's escapes undone).
fn text(html: &str) -> String {
    let mut out = String::new();
    let mut in_tag = false;
    for c in html.chars() {
        match c {
            '<' => in_tag = true,
            '>' => in_tag = false,
            c if !in_tag => out.push(c),
            _ => {}
        }
    }
    out.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&amp;", "&")
}

/// The summary table's body rows, each as its cells' text.
fn summary_rows(html: &str) -> Vec<Vec<String>> {
    let table = between(html, "<table id=\"summary\"", "</table>");
    let body = between(table, "<tbody>", "</tbody>");
    body.split("<tr>")
        .skip(1)
        .map(|row| {
            row.split("<td")
                .skip(1)
                .map(|c| text(&format!("<td{}", c.split("</td>").next().unwrap())))
                .collect()
        })
        .collect()
}

/// The fits' sections: (id, summary line).
fn sections(html: &str) -> Vec<(String, String)> {
    html.split("<details class=\"fit\" id=\"")
        .skip(1)
        .map(|s| {
            let id = s.split('"').next().unwrap().to_string();
            (id, text(between(s, "<summary>", "</summary>")))
        })
        .collect()
}

#[test]
fn by_group_html_is_one_page_with_a_row_and_a_section_per_fit() {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("batch.html");
    let pics = dir.path().join("pics");
    let ptfe = data("nist-ptfe/PTFE.data.csv");
    let args = [
        "fit",
        "--model",
        "lambert",
        "--by-group",
        "--no-intervals",
        ptfe.to_str().unwrap(),
    ];
    common::goniofit()
        .args(args)
        .arg("--html")
        .arg(&page)
        .arg("--plot")
        .arg(&pics)
        .assert()
        .code(0)
        .stderr(contains("one page, 4 fits"));
    let html = std::fs::read_to_string(&page).unwrap();
    // The same fits as the JSON report's summary, in its order.
    let mut json_args = args.to_vec();
    json_args.extend(["--json", "--quiet"]);
    let json = common::fit_json(&json_args);
    let summary = json["summary"].as_array().unwrap();
    let rows = summary_rows(&html);
    let secs = sections(&html);
    assert_eq!(rows.len(), 4);
    assert_eq!(secs.len(), 4);
    for (k, ((row, sec), want)) in rows.iter().zip(&secs).zip(summary).enumerate() {
        let group = want["group"].as_str().unwrap();
        assert_eq!(row[0], (k + 1).to_string());
        assert_eq!(row[1], group);
        assert_eq!(row[2], want["n"].as_str().unwrap());
        let conv = if want["converged"] == "true" {
            "yes"
        } else {
            "no"
        };
        assert_eq!(row[3], conv);
        assert_eq!(sec.0, format!("fit-{}", k + 1));
        assert!(
            sec.1.starts_with(&format!("#{} {group} — ", k + 1)),
            "{}",
            sec.1
        );
        // The row links to its section.
        assert!(html.contains(&format!("<a href=\"#fit-{}\">", k + 1)));
    }
    // Each section holds its report's tables and its pictures inline.
    let first = between(
        &html,
        "<details class=\"fit\" id=\"fit-1\">",
        "</details>\n",
    );
    for part in [
        "<h3>Parameters</h3>",
        "<h3>Pictures</h3>",
        "<svg",
        "hemisphere_1",
    ] {
        assert!(first.contains(part), "{part}");
    }
    // The overview plots every quantity against the four wavelengths (λ differs per fit).
    assert!(html.contains("Each quantity against wavelength (µm)"));
    assert!(html.contains("<figure data-quantity=\"scale\">"));
    // One sortable table, its script inline; no external resource.
    assert!(html.contains("class=\"sortable\"") && html.contains("<script>"));
    assert!(!html.contains("src=\"http") && !html.contains("href=\"http"));
    // One picture folder per fit, in the table's order.
    let mut folders: Vec<String> = std::fs::read_dir(&pics)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    folders.sort();
    assert_eq!(folders.len(), 4);
    assert!(
        folders[0].starts_with("1_PTFE.data.csv_0.351"),
        "{folders:?}"
    );
    for f in &folders {
        for stem in ["fit_log", "hemisphere_1"] {
            assert!(
                pics.join(f).join(format!("{stem}.png")).is_file(),
                "{f}/{stem}"
            );
        }
    }
}

#[test]
fn several_files_make_one_page_and_residuals_still_take_one_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("two.html");
    let (a, b) = (
        data("synthetic/kbs_inplane.csv"),
        data("synthetic/kbs_rough.csv"),
    );
    common::goniofit()
        .args([
            "fit",
            "--model",
            "kbs",
            "--wavelength",
            "1",
            "--no-intervals",
        ])
        .arg("--html")
        .arg(&page)
        .args([&a, &b])
        .assert()
        .code(0);
    let html = std::fs::read_to_string(&page).unwrap();
    assert_eq!(sections(&html).len(), 2);
    let rows = summary_rows(&html);
    assert!(rows[0][1].ends_with("kbs_inplane.csv") && rows[1][1].ends_with("kbs_rough.csv"));
    // Two files of one wavelength: the overview is against the table's rows.
    assert!(html.contains("Each quantity against the fit's row (#) in the summary table"));
    common::goniofit()
        .args(["fit", "--model", "kbs", "--wavelength", "1", "--residuals"])
        .arg(dir.path().join("r.csv"))
        .args([&a, &b])
        .assert()
        .code(2)
        .stderr(contains("--residuals takes one dataset"));
    assert!(!dir.path().join("r.csv").exists());
}

#[test]
fn a_page_without_intervals_does_not_point_at_one() {
    // CUReT surface 1 under kbs+lambert: σ, T and scale are not determined (rough regime).
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("one.html");
    let curet = data("curet/curet.csv");
    common::goniofit()
        .args([
            "fit",
            "--model",
            "kbs+lambert",
            "--wavelength",
            "550nm",
            "--channel",
            "1",
        ])
        .args(["--no-intervals", "--quiet", "--html"])
        .arg(&page)
        .arg(&curet)
        .assert()
        .code(0);
    let html = std::fs::read_to_string(&page).unwrap();
    let params = between(&html, "<h2>Parameters</h2>", "</table>");
    assert!(params.contains("no (no interval computed)"));
    assert!(!params.contains("see the interval"));
}
