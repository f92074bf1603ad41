//! The data's own columns in every output (issue 24 items 4 and 5), by the
//! real binary: the columns a config's `page:` section and `render.color_by`
//! name travel from a CSV table and from hierarchy JSON node properties into
//! the page's data (real nodes only) and the pictures' colours; a column the
//! data lacks is an input error (exit code 2) naming the config line and the
//! column, with the outputs left untouched; `init` offers the keys when the
//! table has such columns.

use std::path::Path;

use crate::support;

/// The page's JSON data block.
fn page_data(html: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(html).expect("read page");
    let start = text.find("class=\"np-data\"").expect("data block");
    let start = start + text[start..].find('>').expect("tag end") + 1;
    let end = start + text[start..].find("</script>").expect("block end");
    serde_json::from_str(&text[start..end]).expect("page data is JSON")
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).expect("write");
}

const NODES: &str = "id,group,size,summary,homepage,score\n\
    a,x,3,\"first, with a comma\",https://a.example/,1.5\n\
    b,x,2,second,javascript:alert(1),-2\n\
    c,y,4,third,,\n\
    d,y,1,fourth,rel/d.html,7\n";

const PAIRS: &str = "a,b\na,b\nc,d\n";

fn config(page: &str, render: &str) -> String {
    format!(
        "render:\n  labels: {{unit: \" KiB\"}}\n{render}datasets:\n  - name: t\n    format: border-list\n\
         \x20   files: {{nodes: nodes.csv, pairs: pairs.csv}}\n\
         \x20   fields: {{weight: size, groups: [group]}}\n{page}\
         \x20   outputs: [out/t.html, out/t.svg]\n"
    )
}

#[test]
fn table_columns_reach_the_page_and_the_colours() {
    let dir = support::temp_dir("render-fields-table");
    write(&dir, "nodes.csv", NODES);
    write(&dir, "pairs.csv", "a,b\nc,d\n");
    let _ = PAIRS;
    write(
        &dir,
        "nptreemap.yaml",
        &config(
            "    page: {fields: [summary, score], link: homepage}\n",
            "  color_by: score\n  color_scale: diverging\n",
        ),
    );
    support::build(&dir.join("nptreemap.yaml"));
    let data = page_data(&dir.join("out/t.html"));
    let nodes = data["nodes"].as_array().expect("nodes");
    let node = |id: &str| nodes.iter().find(|n| n["id"] == id).expect("node");
    assert_eq!(
        node("a")["fields"],
        serde_json::json!([["summary", "first, with a comma"], ["score", "1.5"]])
    );
    assert_eq!(
        node("a")["link"],
        serde_json::json!({"href": "https://a.example/", "ok": true})
    );
    assert_eq!(
        node("b")["link"],
        serde_json::json!({"href": "javascript:alert(1)", "ok": false})
    );
    assert_eq!(node("d")["link"]["ok"], true, "a relative URL is followed");
    // c has no score and no homepage: neither is written.
    assert_eq!(
        node("c")["fields"],
        serde_json::json!([["summary", "third"]])
    );
    assert!(node("c").get("link").is_none());
    // Groups have no fields; the synthetic root is not a row.
    assert!(node("root").get("fields").is_none());
    assert_eq!(data["linkName"], "homepage");
    assert_eq!(data["newTab"], true);

    // Coloured by score on a diverging scale: the SVG's legend shows the
    // scale (-2 to 7) and the grey of c, which has no score.
    let svg = std::fs::read_to_string(dir.join("out/t.svg")).expect("svg");
    assert!(svg.contains(">score: -2</text>"), "{svg}");
    assert!(svg.contains(">7</text>"), "{svg}");
    assert!(svg.contains(">no score value</text>"), "{svg}");
    let fill = |id: &str| {
        let at = svg.find(&format!("data-id=\"{id}\"")).expect("cell");
        let rest = &svg[at..];
        let f = rest.find("fill=\"").expect("fill") + 6;
        rest[f..f + 7].to_owned()
    };
    assert_eq!(fill("c"), "#9e9e9e");
    assert_ne!(fill("a"), fill("d"));
}

#[test]
fn hierarchy_json_properties_reach_the_page() {
    let dir = support::temp_dir("render-fields-json");
    write(
        &dir,
        "h.json",
        r#"{"name": "r", "children": [
            {"name": "g", "children": [
                {"name": "a", "weight": 2, "version": "1.0", "url": "https://a.example/", "stars": 5},
                {"name": "b", "weight": 1, "version": 2, "url": "data:text/html,x"}]},
            {"name": "c", "weight": 3, "version": true}]}"#,
    );
    write(
        &dir,
        "nptreemap.yaml",
        "datasets:\n  - name: h\n    format: hierarchy-json\n    files: {hierarchy: h.json}\n\
         \x20   page: {fields: [version, stars], link: url, link_target: same-tab}\n\
         \x20   outputs: [out/h.html]\n",
    );
    support::build(&dir.join("nptreemap.yaml"));
    let data = page_data(&dir.join("out/h.html"));
    let nodes = data["nodes"].as_array().expect("nodes");
    let node = |label: &str| {
        nodes
            .iter()
            .find(|n| n["label"] == label || n["id"] == label)
            .unwrap_or_else(|| panic!("{label}: {data}"))
    };
    assert_eq!(
        node("a")["fields"],
        serde_json::json!([["version", "1.0"], ["stars", "5"]])
    );
    assert_eq!(node("b")["fields"], serde_json::json!([["version", "2"]]));
    assert_eq!(node("b")["link"]["ok"], false);
    // c is a leaf one level up: the page has it once, with its field (no
    // virtual copies in the page's data).
    assert_eq!(
        node("c")["fields"],
        serde_json::json!([["version", "true"]])
    );
    assert!(
        !nodes
            .iter()
            .any(|n| n["id"].as_str().is_some_and(|i| i.contains("depth"))),
        "{data}"
    );
    assert!(data.get("newTab").is_none());
}

#[test]
fn a_column_the_data_lacks_is_an_error_naming_the_config_line() {
    let dir = support::temp_dir("render-fields-bad");
    write(&dir, "nodes.csv", NODES);
    write(&dir, "pairs.csv", "a,b\n");
    std::fs::create_dir_all(dir.join("out")).expect("out");
    write(&dir, "out/t.html", "old page");
    let text = config("    page: {fields: [summry]}\n", "");
    let line = text
        .lines()
        .position(|l| l.trim_start().starts_with("page:"))
        .expect("page line")
        + 1;
    write(&dir, "nptreemap.yaml", &text);
    let out = support::bin()
        .arg("build")
        .arg(dir.join("nptreemap.yaml"))
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("\"summry\""), "names the column: {err}");
    assert!(
        err.contains(&format!("config line {line}")),
        "names the config line {line}: {err}"
    );
    assert!(err.contains("summary"), "suggests the column: {err}");
    assert_eq!(
        std::fs::read_to_string(dir.join("out/t.html")).expect("page"),
        "old page",
        "outputs untouched"
    );

    // In hierarchy JSON, a property no node has, for color_by.
    write(
        &dir,
        "h.json",
        r#"{"name": "r", "children": [{"name": "a", "weight": 1}]}"#,
    );
    let text = "render:\n  color_by: score\ndatasets:\n  - name: h\n    format: hierarchy-json\n\
                \x20   files: {hierarchy: h.json}\n    outputs: [out/h.svg]\n";
    write(&dir, "h.yaml", text);
    let out = support::bin()
        .arg("build")
        .arg(dir.join("h.yaml"))
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("\"score\"") && err.contains("render.color_by, config line 2"),
        "{err}"
    );
}

#[test]
fn init_offers_the_page_keys_for_such_columns() {
    let dir = support::temp_dir("render-fields-init");
    write(&dir, "nodes.csv", NODES);
    write(&dir, "pairs.csv", "a,b\nc,d\n");
    let out = support::bin()
        .current_dir(&dir)
        .args(["init", "nodes.csv", "pairs.csv"])
        .output()
        .expect("run init");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let config = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("config");
    assert!(config.contains("    # page:\n"), "{config}");
    assert!(config.contains("#   link: homepage"), "{config}");
    assert!(config.contains("summary"), "{config}");
    // Uncommented, the offer is a valid config that builds.
    let uncommented: String = config
        .lines()
        .map(|l| {
            let t = l.trim_start();
            if l.starts_with("    # ") && (t.starts_with("# page:") || t.starts_with("#   ")) {
                l.replacen("# ", "", 1)
            } else {
                l.to_owned()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    write(&dir, "nptreemap.yaml", &(uncommented + "\n"));
    support::build(&dir.join("nptreemap.yaml"));
}

/// Issue 30 item 13: `color_by` over the widest finite range. The legend
/// printed `-inf … inf` and 1e300 as 301 digits, and the 1e308 leaf was
/// drawn black, a colour the scale never makes.
#[test]
fn color_by_takes_any_finite_range_and_prints_it_readably() {
    let dir = support::temp_dir("render-fields-extreme");
    let mut nodes = String::from("id,group,size,score\n");
    for (k, score) in ["-1e308", "1e308", "1e300", "-2", "0", "3", "1", "2"]
        .iter()
        .enumerate()
    {
        nodes.push_str(&format!("n{k},{},1,{score}\n", ["x", "y"][k % 2]));
    }
    write(&dir, "nodes.csv", &nodes);
    write(&dir, "pairs.csv", "n0,n1\n");
    write(
        &dir,
        "nptreemap.yaml",
        &config("", "  color_by: score\n").replace("out/t.html, out/t.svg", "out/t.svg, out/t.png"),
    );
    support::build(&dir.join("nptreemap.yaml"));
    let svg = std::fs::read_to_string(dir.join("out/t.svg")).expect("svg");
    let legend = &svg[svg.find("np-legend").expect("legend")..];
    assert!(!legend.contains("inf"), "{legend}");
    // The two values beyond the fences are outliers: the scale is clipped
    // to the others and the legend says so, in short numbers.
    assert!(
        legend.contains("score (scale clipped at outliers): ≤ -2</text>"),
        "{legend}"
    );
    assert!(legend.contains(">≥ 3</text>"), "{legend}");
    let longest = legend
        .split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(longest < 16, "a number of {longest} digits in {legend}");
    // Every leaf has a colour of the scale, none black.
    assert!(!svg.contains("fill=\"#000000\""), "{svg}");
    let fill = |id: &str| {
        let at = svg.find(&format!("data-id=\"{id}\"")).expect("cell");
        let rest = &svg[at..];
        let f = rest.find("fill=\"").expect("fill") + 6;
        rest[f..f + 7].to_owned()
    };
    // The outliers take the ends of the scale, like the values at the fences.
    assert_eq!(fill("n1"), fill("n5"));
    assert_eq!(fill("n0"), fill("n3"));
    assert_eq!(fill("n2"), fill("n1"));
    assert_ne!(fill("n3"), fill("n5"));
}
