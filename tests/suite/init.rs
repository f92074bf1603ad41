//! `nptreemap init` on hostile or awkward tables: it never writes over one of
//! its inputs, a FIFO or through a dangling link; it reads a bounded sample of
//! a large table and refuses, naming the limit, what `build` would refuse; its
//! guesses (label, groups, genres) and the flags that override them; `.npy`
//! vectors; file names with a newline or `: `.

use std::path::Path;
use std::process::Output;

use crate::cli_conventions::ok;
use crate::support;

fn run_in(dir: &Path, args: &[&str]) -> Output {
    support::output_within(support::bin().args(args).current_dir(dir), 120)
}

/// Asserts exit code 2 and every needle in stderr; returns stderr.
fn refused(out: &Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    for needle in needles {
        assert!(stderr.contains(needle), "no {needle:?} in: {stderr}");
    }
    stderr
}

const NODES: &str = "id,name,size,continent\nDE,Germany,84,EU\nFR,France,68,EU\n\
                     CN,China,1400,AS\nIN,India,1400,AS\n";
const PAIRS: &str = "a,b\nDE,FR\nCN,IN\n";

/// A folder with `nodes.csv` and `pairs.csv`.
fn two_tables(tag: &str) -> std::path::PathBuf {
    let dir = support::temp_dir(tag);
    std::fs::write(dir.join("nodes.csv"), NODES).expect("nodes");
    std::fs::write(dir.join("pairs.csv"), PAIRS).expect("pairs");
    dir
}

/// `nptreemap init nodes.csv pairs.csv -o OUTPUT --force` in `dir`.
fn init_over(dir: &Path, output: &str) -> Output {
    run_in(
        dir,
        &["init", "nodes.csv", "pairs.csv", "-o", output, "--force"],
    )
}

#[test]
fn output_naming_an_input_is_refused_however_it_is_named() {
    let dir = two_tables("init_over_input");
    std::fs::create_dir(dir.join("sub")).expect("sub");
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(dir.join("nodes.csv"), dir.join("link.yaml")).expect("link");
        std::fs::hard_link(dir.join("pairs.csv"), dir.join("hard.yaml")).expect("hard link");
    }
    let mut outputs = vec!["nodes.csv", "sub/../pairs.csv"];
    if cfg!(unix) {
        outputs.extend(["link.yaml", "hard.yaml"]);
    }
    for output in outputs {
        let out = init_over(&dir, output);
        refused(&out, &[output, "input"]);
        assert_eq!(
            std::fs::read_to_string(dir.join("nodes.csv")).expect("nodes"),
            NODES,
            "-o {output}"
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("pairs.csv")).expect("pairs"),
            PAIRS,
            "-o {output}"
        );
    }
    #[cfg(unix)]
    assert!(std::fs::symlink_metadata(dir.join("link.yaml"))
        .expect("link")
        .file_type()
        .is_symlink());
}

#[cfg(unix)]
#[test]
fn output_that_is_a_fifo_or_a_dangling_link_is_refused_without_blocking() {
    use std::os::unix::fs::FileTypeExt;
    let dir = two_tables("init_special_output");
    let fifo = dir.join("fifo.yaml");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo");
    assert!(made.success());
    // A FIFO opened for writing blocks until a reader comes: output_within
    // fails the test instead of hanging it.
    let out = init_over(&dir, "fifo.yaml");
    refused(&out, &["fifo.yaml", "FIFO"]);
    assert!(std::fs::symlink_metadata(&fifo)
        .expect("fifo")
        .file_type()
        .is_fifo());
    // A link to a file that does not exist: nothing is written through it.
    std::os::unix::fs::symlink(dir.join("elsewhere/target.yaml"), dir.join("dangling.yaml"))
        .expect("link");
    std::fs::create_dir(dir.join("elsewhere")).expect("dir");
    for force in [false, true] {
        let mut args = vec!["init", "nodes.csv", "pairs.csv", "-o", "dangling.yaml"];
        if force {
            args.push("--force");
        }
        let out = run_in(&dir, &args);
        refused(&out, &["dangling.yaml", "link"]);
        assert!(!dir.join("elsewhere/target.yaml").exists());
        assert!(std::fs::symlink_metadata(dir.join("dangling.yaml"))
            .expect("link")
            .file_type()
            .is_symlink());
    }
    // A folder is no config file either.
    std::fs::create_dir(dir.join("folder.yaml")).expect("dir");
    let out = init_over(&dir, "folder.yaml");
    refused(&out, &["folder.yaml", "directory"]);
    // And the ordinary case still works, replacing a regular file with --force.
    std::fs::write(dir.join("mine.yaml"), "old").expect("write");
    ok(&init_over(&dir, "mine.yaml"));
    let yaml = std::fs::read_to_string(dir.join("mine.yaml")).expect("written");
    assert!(yaml.contains("format: border-list"), "{yaml}");
}

/// Runs `nptreemap ARGS` in `dir` with at most `mib` MiB of address space.
pub(crate) fn run_capped(dir: &Path, mib: u64, args: &str) -> Output {
    let bin = env!("CARGO_BIN_EXE_nptreemap");
    support::output_within(
        std::process::Command::new("bash")
            .arg("-c")
            .arg(format!("ulimit -v {}; exec {bin} {args}", mib * 1024))
            .current_dir(dir),
        300,
    )
}

#[cfg(unix)]
#[test]
fn a_large_table_is_sampled_and_checked_against_the_limits() {
    use std::io::Write;
    let dir = support::temp_dir("init_large");
    // 1.6 million rows (48 MB) with a genres column: every field is small, so
    // a table read whole costs about 35 bytes of memory per byte of file.
    let mut file =
        std::io::BufWriter::new(std::fs::File::create(dir.join("big.csv")).expect("create"));
    writeln!(file, "id,name,group,genres,value").expect("write");
    for i in 0..1_600_000u32 {
        writeln!(file, "n{i},x{},g{},a|b,{}", i % 997, i % 13, i % 100).expect("write");
    }
    file.flush().expect("flush");
    drop(file);
    let out = run_capped(&dir, 600, "init big.csv");
    refused(&out, &["big.csv", "1600000 rows", "limits.max_nodes"]);
    assert!(!dir.join("nptreemap.yaml").exists());

    // A file over max_file_mb (sparse: no disk is used) is refused unread.
    let huge = std::fs::File::create(dir.join("huge.csv")).expect("create");
    huge.set_len(300 << 20).expect("sparse file");
    let out = run_capped(&dir, 600, "init huge.csv");
    refused(&out, &["huge.csv", "limits.max_file_mb"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn vectors_wider_than_max_dimensions_are_refused() {
    let dir = support::temp_dir("init_wide");
    std::fs::write(dir.join("nodes.csv"), "id,size\na,1\nb,2\nc,3\n").expect("nodes");
    let mut vectors = String::from("id");
    for k in 0..1100 {
        vectors.push_str(&format!(",v{k}"));
    }
    for id in ["a", "b", "c"] {
        vectors.push('\n');
        vectors.push_str(id);
        for k in 0..1100 {
            vectors.push_str(&format!(",{}", (k % 7) + 1));
        }
    }
    vectors.push('\n');
    std::fs::write(dir.join("vectors.csv"), vectors).expect("vectors");
    let out = run_in(&dir, &["init", "nodes.csv", "vectors.csv"]);
    refused(&out, &["vectors.csv", "1100", "limits.max_dimensions"]);
    assert!(!dir.join("nptreemap.yaml").exists());
}

#[test]
fn a_table_larger_than_the_sample_still_finds_its_pairs() {
    // 60,000 nodes (1.4 MB, more than init reads of a table) and pairs that
    // name nodes from all over it.
    let dir = support::temp_dir("init_sampled_pairs");
    let mut nodes = String::from("id,name,size,region\n");
    for i in 0..60_000 {
        nodes.push_str(&format!("node{i},Node {i},{},r{}\n", 1 + i % 50, i % 40));
    }
    let mut pairs = String::from("a,b\n");
    for i in 0..3_000 {
        pairs.push_str(&format!(
            "node{},node{}\n",
            (i * 7919) % 60_000,
            (i * 104_729 + 13) % 60_000
        ));
    }
    std::fs::write(dir.join("nodes.csv"), nodes).expect("nodes");
    std::fs::write(dir.join("pairs.csv"), pairs).expect("pairs");
    ok(&run_in(&dir, &["init", "nodes.csv", "pairs.csv"]));
    let yaml = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("written");
    assert!(yaml.contains("format: border-list"), "{yaml}");
    assert!(yaml.contains("pairs: pairs.csv"), "{yaml}");
}

/// Words for made-up sentences.
const WORDS: [&str; 12] = [
    "quiet", "river", "under", "the", "old", "bridge", "carries", "light", "toward", "evening",
    "and", "stone",
];

fn sentence(i: usize) -> String {
    (0..9)
        .map(|k| WORDS[(i * 5 + k * 7 + k * k) % WORDS.len()])
        .collect::<Vec<_>>()
        .join(" ")
        + &format!(" number {i}.")
}

#[test]
fn guesses_a_short_label_real_groups_and_a_sparse_multi_valued_column() {
    let dir = support::temp_dir("init_guesses");
    // 94 packages: a long description (unique), a short title (unique), its
    // first letter (a derived index, not a grouping), a real grouping column
    // and a `requires` column with `|` in 25 of the 94 cells.
    let deps = ["core", "io", "net", "text", "math"];
    let mut table = String::from("id,description,title,letter,team,downloads,requires\n");
    for i in 0..94 {
        let title = format!(
            "{}pkg{i}",
            ["alpha", "beta", "gamma", "delta", "omega"][i % 5]
        );
        let letter = title[..1].to_uppercase();
        let requires = if i < 25 {
            format!("{}|{}", deps[i % 5], deps[(i + 1) % 5])
        } else if i % 3 == 0 {
            String::new()
        } else {
            deps[i % 5].to_string()
        };
        table.push_str(&format!(
            "p{i},\"{}\",{title},{letter},team{},{},{requires}\n",
            sentence(i),
            i % 6,
            100 + i
        ));
    }
    assert_eq!(table.matches('|').count(), 25);
    std::fs::write(dir.join("packages.csv"), &table).expect("table");
    ok(&run_in(&dir, &["init", "packages.csv"]));
    let yaml = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("written");
    assert!(yaml.contains("format: genre-table"), "{yaml}");
    assert!(yaml.contains("genres: requires"), "{yaml}");
    assert!(yaml.contains("label: title"), "{yaml}");
    assert!(yaml.contains("- team"), "{yaml}");
    assert!(
        !yaml.contains("- letter"),
        "a first-letter column as a group:\n{yaml}"
    );
    assert!(!yaml.contains("label: description"), "{yaml}");
    // What init wrote builds.
    ok(&run_in(&dir, &["check"]));
}

#[test]
fn flags_override_the_guesses_and_unknown_columns_get_a_did_you_mean() {
    let dir = support::temp_dir("init_flags");
    std::fs::write(
        dir.join("films.csv"),
        "id,title,director,studio,runtime,budget,genres,tags\n\
         a,Alpha,Ann,S1,100,5,Drama|Crime,x|y\n\
         b,Beta,Ann,S1,90,7,Drama,y|z\n\
         c,Gamma,Bob,S2,120,9,Crime|Action,x|z\n\
         d,Delta,Bob,S2,95,3,Action,x\n",
    )
    .expect("table");
    ok(&run_in(
        &dir,
        &[
            "init",
            "films.csv",
            "--label",
            "id",
            "--weight",
            "budget",
            "--groups",
            "studio,director",
            "--genres",
            "tags",
        ],
    ));
    let yaml = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("written");
    for wanted in ["label: id", "weight: budget", "genres: tags"] {
        assert!(yaml.contains(wanted), "no {wanted:?} in\n{yaml}");
    }
    let studio = yaml.find("- studio").expect("studio is a group");
    let director = yaml.find("- director").expect("director is a group");
    assert!(studio < director, "outermost first:\n{yaml}");
    ok(&run_in(&dir, &["check"]));
    // `--groups=` leaves out the grouping.
    ok(&run_in(
        &dir,
        &["init", "films.csv", "--groups=", "--force"],
    ));
    let yaml = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("written");
    assert!(!yaml.contains("director"), "{yaml}");
    for (flag, value, wanted) in [
        ("--label", "titel", "did you mean \"title\"?"),
        ("--weight", "runtim", "did you mean \"runtime\"?"),
        ("--groups", "directr", "did you mean \"director\"?"),
        ("--genres", "genre", "did you mean \"genres\"?"),
        ("--weight", "title", "not a number"),
    ] {
        std::fs::write(dir.join("nptreemap.yaml"), "kept").expect("write");
        let out = run_in(&dir, &["init", "films.csv", flag, value, "--force"]);
        refused(&out, &[flag, value, "films.csv", wanted]);
        assert_eq!(
            std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("read"),
            "kept"
        );
    }
}

/// A `.npy` file (version 1.0, little-endian float64) as `numpy.save` writes it.
fn npy(rows: usize, cols: usize, value: impl Fn(usize, usize) -> f64) -> Vec<u8> {
    let mut header =
        format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({rows}, {cols}), }}");
    // The preamble (10 bytes), the header and its newline fill a multiple of 64.
    let pad = (64 - (10 + header.len() + 1) % 64) % 64;
    header.push_str(&" ".repeat(pad));
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend(u16::try_from(header.len()).expect("short").to_le_bytes());
    out.extend(header.as_bytes());
    for i in 0..rows {
        for j in 0..cols {
            out.extend(value(i, j).to_le_bytes());
        }
    }
    out
}

#[test]
fn a_npy_matrix_is_taken_as_the_vectors() {
    let dir = support::temp_dir("init_npy");
    std::fs::write(
        dir.join("docs.csv"),
        "id,label,words,topic\nd1,One,10,a\nd2,Two,20,a\nd3,Three,30,b\nd4,Four,40,b\n",
    )
    .expect("nodes");
    std::fs::write(
        dir.join("embeddings.npy"),
        npy(4, 3, |i, j| 1.0 + (i * 3 + j) as f64 % 5.0),
    )
    .expect("npy");
    ok(&run_in(&dir, &["init", "docs.csv", "embeddings.npy"]));
    let yaml = std::fs::read_to_string(dir.join("nptreemap.yaml")).expect("written");
    assert!(yaml.contains("format: embedding-matrix"), "{yaml}");
    assert!(yaml.contains("vectors: embeddings.npy"), "{yaml}");
    ok(&run_in(&dir, &["build"]));
    assert!(dir.join("out/docs.svg").is_file());
    // A matrix whose rows do not match the table's is refused, saying so.
    std::fs::write(dir.join("short.npy"), npy(3, 3, |_, _| 1.0)).expect("npy");
    let out = run_in(&dir, &["init", "docs.csv", "short.npy", "--force"]);
    refused(&out, &["short.npy", "3 rows", "4"]);
}

#[cfg(unix)]
#[test]
fn file_names_with_a_newline_or_a_colon_make_a_config_that_builds() {
    let dir = support::temp_dir("init_odd_names");
    let nodes = "na: me #1.csv";
    let pairs = "pa\nirs.csv";
    std::fs::write(dir.join(nodes), NODES).expect("nodes");
    std::fs::write(dir.join(pairs), PAIRS).expect("pairs");
    ok(&run_in(&dir, &["init", nodes, pairs]));
    let out = run_in(&dir, &["build"]);
    ok(&out);
    assert!(dir.join("out").read_dir().expect("out").count() >= 2);
}

/// `nptreemap init ARGS -o nptreemap.yaml` in `dir`, which must succeed;
/// returns the config written, parsed, and its text.
fn init_config(dir: &Path, args: &[&str]) -> (nptreemap::config::Config, String) {
    let mut all = vec!["init"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["-o", "nptreemap.yaml", "--force"]);
    ok(&run_in(dir, &all));
    let path = dir.join("nptreemap.yaml");
    let text = std::fs::read_to_string(&path).expect("config");
    let config = nptreemap::config::Config::from_path(&path).expect("the config parses");
    (config, text)
}

/// Rows shaped like `dpkg-query`'s: a unique name, a section that repeats,
/// a version that mostly does not, and a free-text summary.
fn packages_table() -> String {
    let mut s = String::from("name,section,size,version,summary\n");
    for i in 0..40 {
        s.push_str(&format!(
            "pkg{i},{},{},{}.{}-1,\"tools and libraries for the {i}th thing this package does\"\n",
            ["libs", "admin", "utils", "net"][i % 4],
            100 + i * 37,
            i % 7,
            i % 4,
        ));
    }
    s
}

#[test]
fn init_takes_no_group_from_free_text_or_versions() {
    let dir = support::temp_dir("init_packages");
    std::fs::write(dir.join("packages.csv"), packages_table()).expect("nodes");
    let pairs: String = (1..40).map(|i| format!("pkg{i},pkg{}\n", i / 2)).collect();
    std::fs::write(dir.join("depends.csv"), format!("a,b\n{pairs}")).expect("pairs");
    let (config, text) = init_config(&dir, &["packages.csv", "depends.csv"]);
    let fields = &config.datasets[0].fields;
    assert_eq!(fields.groups, ["section"], "{text}");
    assert_eq!(fields.id.as_deref(), Some("name"));
    assert_eq!(fields.weight.as_deref(), Some("size"));
    // Each column left out says why.
    assert!(
        text.contains("not a grouping: summary (free text"),
        "{text}"
    );
    assert!(text.contains("not a grouping: version ("), "{text}");
    assert!(!text.contains("label: version"), "{text}");
    // Short text is offered for the tooltip; the summary is a line of it.
    assert!(text.contains("#     - summary"), "{text}");
}

/// Crates: an id, a name that repeats across versions, a category, a
/// repository URL and dependencies as a set.
fn crates_table() -> String {
    let mut s = String::from("id,name,version,category,url,deps\n");
    for i in 0..30 {
        let name = format!("crate{}", i % 26);
        let version = format!("{}.0.{i}", i % 3);
        s.push_str(&format!(
            "{name}-{version},{name},{version},{},https://github.com/o/{name},dep{}|dep{}\n",
            ["parsing", "encoding", "os"][i % 3],
            i % 5,
            i % 4
        ));
    }
    s
}

#[test]
fn init_makes_a_repeating_label_unique_and_offers_a_url_as_the_link() {
    let dir = support::temp_dir("init_crates");
    std::fs::write(dir.join("crates.csv"), crates_table()).expect("nodes");
    let (config, text) = init_config(&dir, &["crates.csv"]);
    let d = &config.datasets[0];
    assert_eq!(d.fields.groups, ["category"], "{text}");
    assert_eq!(d.fields.label.as_deref(), Some("name"));
    assert_eq!(
        config.render.labels.text,
        nptreemap::render::LabelText::parse("{name} {version}").expect("template"),
        "{text}"
    );
    assert!(
        text.contains("label name is not unique (26 distinct values in 30 rows)"),
        "{text}"
    );
    assert!(text.contains("not a grouping: url (links"), "{text}");
    assert!(text.contains("#   link: url"), "{text}");
    // Built, every label is its own.
    support::build(&dir.join("nptreemap.yaml"));
    let svg = std::fs::read_to_string(dir.join("out/crates.svg")).expect("svg");
    assert!(
        svg.contains("crate1 0.0.27") || svg.contains("crate1 1.0.1"),
        "labels"
    );
}

#[test]
fn init_on_module_tables_groups_by_package_and_labels_by_segment() {
    let dir = support::temp_dir("init_modules");
    // Shaped like the standard library's modules and a site-packages
    // folder's: dotted ids, the package repeating.
    let mut nodes = String::from("module,package,size\n");
    let mut pairs = String::from("a,b\n");
    for (p, package) in ["email", "xml.etree", "json", "http", "urllib"]
        .iter()
        .enumerate()
    {
        for m in 0..6 {
            nodes.push_str(&format!("{package}.m{m},{package},{}\n", 100 + 13 * m + p));
            if m > 0 {
                pairs.push_str(&format!("{package}.m{m},{package}.m0\n"));
            }
        }
    }
    std::fs::write(dir.join("modules.csv"), nodes).expect("nodes");
    std::fs::write(dir.join("imports.csv"), pairs).expect("pairs");
    let (config, text) = init_config(&dir, &["modules.csv", "imports.csv"]);
    let fields = &config.datasets[0].fields;
    assert_eq!(fields.id.as_deref(), Some("module"), "{text}");
    assert_eq!(fields.groups, ["package"], "{text}");
    support::build(&dir.join("nptreemap.yaml"));
    let svg = std::fs::read_to_string(dir.join("out/modules.svg")).expect("svg");
    // Cells keep the whole name in their tooltip (`<title>`); labels do not.
    let texts: Vec<&str> = svg
        .split("<text")
        .skip(1)
        .filter_map(|t| t.split("</text>").next())
        .collect();
    assert!(texts.iter().any(|t| t.ends_with(">m0")), "{texts:?}");
    assert!(
        !texts.iter().any(|t| t.contains("xml.etree.m")),
        "a label repeats its package: {texts:?}"
    );
    assert!(svg.contains("<title>xml.etree.m0</title>"));
}
