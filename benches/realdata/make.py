#!/usr/bin/env python3
"""Real hierarchies from this machine, as nptreemap input folders.

Owns the generation of the real-data corpus (benches/realdata/README.md and
tests/data/real/README.md describe it): each dataset is read from files that
exist on a Debian machine with Python and a Cargo registry, turned into one of
nptreemap's input formats, and written with its own `nptreemap.yaml` (outputs
into `out/` beside it) to `--out DIR/<name>/` (default `target/realdata`).

Datasets (`--only a,b` picks some, `--list` names them):

  debian-packages  genre-table       /var/lib/dpkg/status: Section > package,
                                     weight Installed-Size, genres = Depends names
  python-stdlib    border-list       the running interpreter's stdlib (tests left
                                     out): package > module, weight bytes, pairs =
                                     import edges
  rust-crates      hierarchy-json    ~/.cargo/registry/src/*/*/src/**.rs: crate >
                                     top module dir > file, weight lines, 32-d
                                     hashed TF-IDF of identifiers
  copyright-docs   embedding-matrix  /usr/share/doc/*/copyright: Section > package,
                                     weight bytes, 48-d hashed TF-IDF (licence texts
                                     repeat: exact duplicate vectors)
  man-pages        embedding-matrix  /usr/share/man/man{5,7,8}: section > package >
                                     page, weight bytes, 32-d hashed TF-IDF; `.so`
                                     redirect pages have no text: nptreemap.yaml gives
                                     them their target's vector, zero-vectors.yaml
                                     keeps their zero vectors
  usr-bin          embedding-matrix  /usr/bin flat (one sibling group of ~1,000),
                                     weight file size, 32-d hashed name trigrams;
                                     id-header.yaml reads the same vectors with an
                                     `id` header (a program is called `id`)

Only the Python standard library is used. Deterministic: every directory listing
is sorted, hashing is crc32, floats are printed with fixed precision and no
timestamps are written, so the same machine gives the same bytes. No document
text is written, only ids, sizes, names and derived vectors.

usage: make.py [--out DIR] [--only NAMES] [--list]
"""
import argparse
import ast
import csv
import gzip
import io
import json
import math
import os
import re
import sys
import sysconfig
import zlib
from pathlib import Path

OUTPUTS = ("svg", "png", "json", "html")


# ---------------------------------------------------------------- helpers


def write_csv(path, header, rows, delimiter=","):
    """Writes an RFC 4180 table (LF line ends) with a header row."""
    buf = io.StringIO()
    w = csv.writer(buf, delimiter=delimiter, lineterminator="\n", quoting=csv.QUOTE_MINIMAL)
    w.writerow(header)
    for r in rows:
        w.writerow(r)
    path.write_text(buf.getvalue(), encoding="utf-8")


def fmt(x):
    """A vector component with fixed precision; -0 printed as 0."""
    s = f"{x:.4f}"
    return "0" if s in ("0.0000", "-0.0000") else s.rstrip("0").rstrip(".")


def write_vectors(path, ids, vectors, id_header="id"):
    """Writes `id<TAB>v1..vd` rows with a header (`id`, d0, d1, ...)."""
    dim = len(vectors[0]) if vectors else 0
    lines = ["\t".join([id_header] + [f"d{i}" for i in range(dim)])]
    for i, v in zip(ids, vectors):
        lines.append("\t".join([i] + [fmt(x) for x in v]))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def write_config(folder, header, datasets, layout=None, filename="nptreemap.yaml"):
    """Writes a config (`nptreemap.yaml`): a comment header, one entry per dataset.

    `datasets` holds dicts with name, title, format, files (role -> file) and
    fields (key -> value or list); outputs are out/<name>.{svg,png,json,html}.
    """
    lines = [f"# {l}" if l else "#" for l in header]
    lines.append(f"# Build with: nptreemap build {folder.name}/{filename}")
    if layout:
        lines.append("layout:")
        for k, v in layout.items():
            lines.append(f"  {k}: {v}")
    lines.append("datasets:")
    for d in datasets:
        lines.append(f"  - name: {d['name']}")
        lines.append(f"    title: {json.dumps(d['title'])}")
        lines.append(f"    format: {d['format']}")
        lines.append("    files:")
        for role, f in d["files"].items():
            lines.append(f"      {role}: {f}")
        if d.get("fields"):
            lines.append("    fields:")
            for k, v in d["fields"].items():
                if isinstance(v, list):
                    v = "[" + ", ".join(v) + "]"
                lines.append(f"      {k}: {v}")
        if d.get("similarity"):
            lines.append(f"    similarity: {d['similarity']}")
        lines.append("    outputs:")
        for ext in OUTPUTS:
            lines.append(f"      - path: out/{d['name']}.{ext}")
    (folder / filename).write_text("\n".join(lines) + "\n", encoding="utf-8")


def hashed_tfidf(docs, dim, salt=""):
    """Hashed TF-IDF vectors, L2-normalised (a zero vector stays zero).

    `docs` is a list of token lists. A token's bucket is crc32(salt + token) % dim;
    tf is 1 + ln(count), idf is ln(N / df), so a term in every document weighs 0
    and an empty document gives the zero vector (as a real pipeline would).
    """
    n = len(docs)
    counts = []
    df = {}
    for toks in docs:
        c = {}
        for t in toks:
            c[t] = c.get(t, 0) + 1
        counts.append(c)
        for t in c:
            df[t] = df.get(t, 0) + 1
    bucket = {t: zlib.crc32((salt + t).encode("utf-8")) % dim for t in df}
    out = []
    for c in counts:
        v = [0.0] * dim
        for t, k in c.items():
            w = (1.0 + math.log(k)) * math.log(n / df[t])
            v[bucket[t]] += w
        norm = math.sqrt(sum(x * x for x in v))
        out.append([x / norm for x in v] if norm > 0 else v)
    return out


def vector_facts(ids, vectors):
    """Counts of zero vectors and of exact duplicates (as printed)."""
    keys = ["\t".join(fmt(x) for x in v) for v in vectors]
    zero = sum(1 for v in vectors if all(fmt(x) == "0" for x in v))
    seen = {}
    for k in keys:
        seen[k] = seen.get(k, 0) + 1
    dup_rows = sum(c for c in seen.values() if c > 1)
    dup_groups = sum(1 for c in seen.values() if c > 1)
    return {
        "zero_vectors": zero,
        "rows_with_an_identical_vector": dup_rows,
        "distinct_duplicated_vectors": dup_groups,
        "largest_identical_vector_set": max(seen.values()) if seen else 0,
        "dims": len(vectors[0]) if vectors else 0,
    }


def tree_facts(leaf_parent, weights, parents_of_groups):
    """Shape figures from leaf -> parent group and group -> parent group maps.

    parents_of_groups maps each internal node id to its parent id (None for
    the root). Returns leaves, internal nodes, depth, largest sibling group,
    weight ratio (max/min over positive weights) and zero-weight leaves.
    """
    children = {}
    for leaf, p in leaf_parent.items():
        children.setdefault(p, []).append(leaf)
    for g, p in parents_of_groups.items():
        if p is not None:
            children.setdefault(p, []).append(g)

    def depth(node):
        d = 0
        while node in leaf_parent or parents_of_groups.get(node) is not None:
            node = leaf_parent.get(node) if node in leaf_parent else parents_of_groups[node]
            d += 1
        return d

    biggest = max(children.items(), key=lambda kv: (len(kv[1]), kv[0]))
    pos = [w for w in weights.values() if w > 0]
    top = [g for g, p in parents_of_groups.items() if p is not None and parents_of_groups.get(p) is None]
    return {
        "leaves": len(leaf_parent),
        "groups_top_level": len(top),
        "internal_nodes": len(parents_of_groups),
        "max_leaf_depth": max(depth(l) for l in leaf_parent),
        "min_leaf_depth": min(depth(l) for l in leaf_parent),
        "largest_sibling_group": len(biggest[1]),
        "largest_sibling_group_parent": biggest[0],
        "weight_min_positive": min(pos),
        "weight_max": max(pos),
        "weight_ratio": round(max(pos) / min(pos), 1),
        "zero_weight_leaves": sum(1 for w in weights.values() if w == 0),
    }


def grouped_facts(rows, group_cols, weight):
    """tree_facts for a node table grouped by columns (the table format's ids)."""
    parents = {"root": None}
    leaf_parent = {}
    weights = {}
    for r in rows:
        p = "root"
        vals = []
        for c in group_cols:
            vals.append(r[c])
            g = "group:" + "/".join(vals)
            parents.setdefault(g, p)
            p = g
        leaf_parent[r["id"]] = p
        weights[r["id"]] = r[weight]
    return tree_facts(leaf_parent, weights, parents)


# ---------------------------------------------------------------- dpkg


def read_dpkg_status(path="/var/lib/dpkg/status"):
    """Paragraphs of the dpkg status file as dicts (continuation lines joined)."""
    text = Path(path).read_text(encoding="utf-8", errors="replace")
    paras = []
    for block in text.split("\n\n"):
        fields = {}
        key = None
        for line in block.split("\n"):
            if not line:
                continue
            if line[0] in " \t" and key:
                fields[key] += "\n" + line
                continue
            if ":" in line:
                key, _, val = line.partition(":")
                fields[key] = val.strip()
        if "Package" in fields:
            paras.append(fields)
    return paras


def dep_names(field):
    """Package names in a Depends-style field: alternatives too, no versions/arch."""
    names = set()
    for part in re.split(r"[,|]", field or ""):
        part = re.sub(r"\(.*?\)|\[.*?\]|<.*?>", "", part).strip()
        if part:
            names.add(part.split(":")[0])
    return names


def installed_packages():
    """Installed packages: {name: paragraph}, name:arch when a name repeats."""
    paras = [p for p in read_dpkg_status() if p.get("Status", "").endswith(" installed")]
    count = {}
    for p in paras:
        count[p["Package"]] = count.get(p["Package"], 0) + 1
    out = {}
    for p in paras:
        key = p["Package"] if count[p["Package"]] == 1 else f"{p['Package']}:{p.get('Architecture', '')}"
        out[key] = p
    return dict(sorted(out.items()))


def section_of(p):
    """A paragraph's Section without the archive area prefix (contrib/, non-free/)."""
    return p.get("Section", "unknown").split("/")[-1] or "unknown"


def make_debian_packages(folder):
    """debian-packages: genre-table of installed packages by Section."""
    rows = []
    for name, p in installed_packages().items():
        deps = dep_names(p.get("Depends")) | dep_names(p.get("Pre-Depends"))
        deps.discard(name)
        rows.append({
            "id": name,
            "label": p["Package"],
            "section": section_of(p),
            "priority": p.get("Priority", "unknown"),
            "source": (p.get("Source") or p["Package"]).split(" ")[0],
            "installed_size_kib": int(p.get("Installed-Size", "0") or 0),
            "depends": "|".join(sorted(deps)),
        })
    cols = ["id", "label", "section", "priority", "source", "installed_size_kib", "depends"]
    write_csv(folder / "packages.csv", cols, [[r[c] for c in cols] for r in rows])
    write_config(folder, [
        "Debian packages installed on the machine that ran benches/realdata/make.py,",
        "grouped by Section, sized by Installed-Size (KiB), similar when their",
        "Depends + Pre-Depends name sets overlap (Jaccard; alternatives included).",
    ], [{
        "name": "debian-packages",
        "title": "Installed Debian packages by size; neighbours share dependencies",
        "format": "genre-table",
        "files": {"nodes": "packages.csv"},
        "fields": {"weight": "installed_size_kib", "groups": ["section"], "genres": "depends"},
    }])
    facts = grouped_facts(rows, ["section"], "installed_size_kib")
    sets = {}
    for r in rows:
        sets[r["depends"]] = sets.get(r["depends"], 0) + 1
    facts.update({
        "source": "/var/lib/dpkg/status",
        "format": "genre-table",
        "empty_genre_sets": sets.get("", 0),
        "rows_sharing_an_identical_nonempty_genre_set": sum(c for k, c in sets.items() if k and c > 1),
        "largest_identical_genre_set": max(c for k, c in sets.items() if k),
        "distinct_genres": len({g for r in rows for g in r["depends"].split("|") if g}),
    })
    return facts


# ---------------------------------------------------------------- python


SKIP_DIRS = {"test", "tests", "idle_test", "site-packages", "__pycache__"}


def stdlib_modules(root):
    """{dotted module name: path} for the stdlib's .py files, tests left out."""
    mods = {}
    for dirpath, dirnames, filenames in os.walk(root):
        rel = Path(dirpath).relative_to(root)
        # Only packages (folders with __init__.py): skips lib-dynload, config-*, data folders.
        dirnames[:] = sorted(d for d in dirnames
                             if d not in SKIP_DIRS and Path(dirpath, d, "__init__.py").exists())
        for f in sorted(filenames):
            if not f.endswith(".py"):
                continue
            parts = list(rel.parts) + [f[:-3]]
            if parts[-1] == "__init__":
                parts = parts[:-1]
            if not parts or any("-" in p for p in parts):
                continue
            mods[".".join(parts)] = Path(dirpath, f)
    return dict(sorted(mods.items()))


def resolve_import(name, mods):
    """The longest prefix of a dotted name that is one of our modules."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        cand = ".".join(parts[:k])
        if cand in mods:
            return cand
    return None


def module_imports(mod, path, mods):
    """Modules of the set that `mod` imports (any import statement, anywhere)."""
    try:
        tree = ast.parse(path.read_bytes(), filename=str(path))
    except (SyntaxError, ValueError):
        return set()
    is_pkg = path.name == "__init__.py"
    package = mod if is_pkg else mod.rpartition(".")[0]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                found.add(resolve_import(a.name, mods))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".") if package else []
                base = base[: len(base) - (node.level - 1)] if node.level > 1 else base
                prefix = ".".join(base + ([node.module] if node.module else []))
            else:
                prefix = node.module or ""
            for a in node.names:
                target = resolve_import(f"{prefix}.{a.name}", mods) if prefix else resolve_import(a.name, mods)
                found.add(target)
    found.discard(None)
    found.discard(mod)
    return found


def make_python_stdlib(folder, stdlib):
    """python-stdlib: border-list of stdlib modules with import edges."""
    mods = stdlib_modules(stdlib)
    rows = []
    pairs = set()
    for mod, path in mods.items():
        data = path.read_bytes()
        top = mod.split(".")[0]
        is_pkg = path.name == "__init__.py" or "." in mod
        rows.append({
            "id": mod,
            "label": mod.rpartition(".")[2] + ("/__init__" if path.name == "__init__.py" else ""),
            "package": top if is_pkg else "(top level)",
            "bytes": len(data),
            "lines": data.count(b"\n"),
        })
        for other in module_imports(mod, path, mods):
            pairs.add(tuple(sorted((mod, other))))
    cols = ["id", "label", "package", "bytes", "lines"]
    write_csv(folder / "modules.csv", cols, [[r[c] for c in cols] for r in rows])
    write_csv(folder / "imports.csv", ["a", "b"], sorted(pairs))
    write_config(folder, [
        f"Python {sys.version.split()[0]} standard library modules (tests left out),",
        "grouped by top-level package (single-file modules in '(top level)'), sized",
        "by bytes (empty __init__.py files weigh 0), neighbours when one imports",
        "the other (any import statement, resolved to the longest module prefix).",
    ], [{
        "name": "python-stdlib",
        "title": f"Python {sys.version_info.major}.{sys.version_info.minor} standard library by bytes; neighbours import each other",
        "format": "border-list",
        "files": {"nodes": "modules.csv", "pairs": "imports.csv"},
        "fields": {"weight": "bytes", "groups": ["package"]},
    }])
    facts = grouped_facts(rows, ["package"], "bytes")
    deg = {}
    for a, b in pairs:
        deg[a] = deg.get(a, 0) + 1
        deg[b] = deg.get(b, 0) + 1
    hub = max(deg.items(), key=lambda kv: (kv[1], kv[0]))
    facts.update({
        "source": str(stdlib),
        "format": "border-list",
        "pairs": len(pairs),
        "modules_without_pairs": sum(1 for r in rows if r["id"] not in deg),
        "max_pairs_of_one_module": f"{hub[1]} ({hub[0]})",
    })
    return facts


# ---------------------------------------------------------------- rust


IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]+")
SKIP_CRATES = re.compile(r"^(libc|linux-raw-sys)-\d")


def rust_files(registry):
    """[(crate dir, path under src/)] of every src/**.rs in the registry."""
    out = []
    for index in sorted(p for p in registry.iterdir() if p.is_dir()):
        for crate in sorted(p for p in index.iterdir() if p.is_dir()):
            if SKIP_CRATES.match(crate.name):
                continue
            src = crate / "src"
            if not src.is_dir():
                continue
            for dirpath, dirnames, filenames in os.walk(src):
                dirnames.sort()
                for f in sorted(filenames):
                    if f.endswith(".rs"):
                        out.append((crate, Path(dirpath, f).relative_to(src)))
    return out


def make_rust_crates(folder, registry):
    """rust-crates: hierarchy-json crate > top module dir > file, lines, TF-IDF."""
    files = rust_files(registry)
    docs, meta = [], []
    for crate, rel in files:
        text = (crate / "src" / rel).read_text(encoding="utf-8", errors="replace")
        docs.append([t.lower() for t in IDENT.findall(text)])
        meta.append((crate.name, rel, text.count("\n")))
    vecs = hashed_tfidf(docs, 32, salt="rs:")
    crates = {}
    for (cname, rel, lines), v in zip(meta, vecs):
        node = crates.setdefault(cname, {"id": cname, "name": re.sub(r"-\d[\w.+-]*$", "", cname), "children": {}})
        leaf = {"id": f"{cname}/{rel.as_posix()}", "name": rel.name, "lines": lines,
                "embeddings": [float(fmt(x)) for x in v]}
        if len(rel.parts) == 1:
            node["children"][rel.as_posix()] = leaf
        else:
            d = rel.parts[0]
            sub = node["children"].setdefault(d + "/", {"id": f"{cname}/{d}", "name": d + "/", "children": {}})
            leaf["name"] = Path(*rel.parts[1:]).as_posix()
            sub["children"][rel.as_posix()] = leaf

    def finish(n):
        if "children" in n:
            n["children"] = [finish(c) for _, c in sorted(n["children"].items())]
        return n

    root = {"id": "registry", "name": "cargo registry", "weightAttribute": "lines",
            "simAttribute": "embeddings", "similarityMeasure": "cosine",
            "children": [finish(c) for _, c in sorted(crates.items())]}
    text = json.dumps(root, ensure_ascii=False, separators=(",", ":"))
    text = text.replace(',{"id"', ',\n{"id"')  # one node a line: readable diffs
    (folder / "crates.json").write_text(text + "\n", encoding="utf-8")
    write_config(folder, [
        "Rust source files of the crates in the Cargo registry of the machine that",
        "ran make.py (libc and linux-raw-sys, generated FFI bindings, left out):",
        "crate > top module directory > file, sized by lines, similar by the cosine",
        "of 32-d hashed TF-IDF vectors of their identifiers.",
    ], [{
        "name": "rust-crates",
        "title": "Rust crate sources by lines; neighbours use the same identifiers",
        "format": "hierarchy-json",
        "files": {"hierarchy": "crates.json"},
    }])
    leaf_parent, weights, parents = {}, {}, {"registry": None}
    for c in root["children"]:
        parents[c["id"]] = "registry"
        for k in c["children"]:
            if "children" in k:
                parents[k["id"]] = c["id"]
                for l in k["children"]:
                    leaf_parent[l["id"]] = k["id"]
                    weights[l["id"]] = l["lines"]
            else:
                leaf_parent[k["id"]] = c["id"]
                weights[k["id"]] = k["lines"]
    facts = tree_facts(leaf_parent, weights, parents)
    facts.update({"source": str(registry), "format": "hierarchy-json"})
    facts.update(vector_facts([m[0] for m in meta], vecs))
    return facts


# ---------------------------------------------------------------- docs


WORD = re.compile(r"[a-z][a-z0-9]+")


def make_copyright_docs(folder):
    """copyright-docs: embedding-matrix of /usr/share/doc/*/copyright by Section."""
    pkgs = installed_packages()
    section = {}
    for key, p in pkgs.items():
        section.setdefault(p["Package"], section_of(p))
    rows, docs = [], []
    doc = Path("/usr/share/doc")
    for d in sorted(doc.iterdir()):
        f = d / "copyright"
        if not f.is_file():
            continue
        data = f.read_bytes()
        text = data.decode("utf-8", errors="replace")
        lic = re.search(r"^License:\s*(\S[^\n]*)", text, re.M)
        rows.append({"id": d.name, "label": d.name, "section": section.get(d.name, "(not a package)"),
                     "bytes": len(data), "first_license": lic.group(1).strip()[:40] if lic else "",
                     "doc_dir_is_symlink": "yes" if d.is_symlink() else "no"})
        docs.append(WORD.findall(text.lower()))
    vecs = hashed_tfidf(docs, 48, salt="doc:")
    cols = ["id", "label", "section", "bytes", "first_license", "doc_dir_is_symlink"]
    write_csv(folder / "docs.csv", cols, [[r[c] for c in cols] for r in rows])
    write_vectors(folder / "vectors.tsv", [r["id"] for r in rows], vecs)
    write_config(folder, [
        "The Debian copyright file of every /usr/share/doc/<package>/ (symlinked doc",
        "directories followed, as a reader would), grouped by the package's Section,",
        "sized by bytes, similar by the cosine of 48-d hashed TF-IDF vectors of the",
        "text. Only the vectors are stored, not the text. Licence texts repeat, so",
        "many rows have identical vectors.",
    ], [{
        "name": "copyright-docs",
        "title": "Debian copyright files by size; neighbours have similar text",
        "format": "embedding-matrix",
        "files": {"nodes": "docs.csv", "vectors": "vectors.tsv"},
        "fields": {"weight": "bytes", "groups": ["section"]},
    }])
    facts = grouped_facts(rows, ["section"], "bytes")
    facts.update({"source": "/usr/share/doc/*/copyright", "format": "embedding-matrix"})
    facts.update(vector_facts([r["id"] for r in rows], vecs))
    return facts


ROFF_ESCAPE = re.compile(r"\\(\(..|\[[^\]]*\]|[fFs]\(..|[fFs]\[[^\]]*\]|[fFs][-+]?\d?.|\*.|n.|.)")
TEXT_MACROS = {"SH", "SS", "B", "I", "BI", "BR", "IB", "IR", "RB", "RI", "SM", "SB", "IP", "TP",
               "Nm", "Nd", "Ar", "Fl", "Op", "Pa", "Xr", "Sh", "Ss", "It", "Dl", "Cm", "Em", "Va"}


def man_text(raw):
    """The words of a roff page: request lines dropped except text macros' arguments."""
    words = []
    for line in raw.splitlines():
        if line.startswith((".", "'")):
            parts = line[1:].split(None, 1)
            if not parts or parts[0] not in TEXT_MACROS or len(parts) < 2:
                continue
            line = parts[1]
        words.append(ROFF_ESCAPE.sub(" ", line))
    return " ".join(words)


def read_man(path):
    """A man page's bytes, gunzipped when needed."""
    data = path.read_bytes()
    return gzip.decompress(data) if path.suffix == ".gz" else data


def so_target(raw):
    """The target of a `.so` redirect page (the first request line), else None."""
    for line in raw.splitlines():
        if line.startswith(".so "):
            return line[4:].strip()
        if line.strip() and not line.startswith('.\\"'):
            return None
    return None


def dpkg_owners():
    """{absolute path: package} from /var/lib/dpkg/info/*.list."""
    owners = {}
    for lst in sorted(Path("/var/lib/dpkg/info").glob("*.list")):
        pkg = lst.name[: -len(".list")].split(":")[0]
        for line in lst.read_text(encoding="utf-8", errors="replace").splitlines():
            owners.setdefault(line, pkg)
    return owners


def make_man_pages(folder, sections=("5", "7", "8")):
    """man-pages: embedding-matrix of English man pages, section > package > page.

    A page's package is the owner of its path, else of the file it resolves to
    (pages installed through /etc/alternatives are owned by their target's package).
    """
    owners = dpkg_owners()
    man = Path("/usr/share/man")
    rows, raw_docs, resolved_docs = [], [], []
    for s in sections:
        for f in sorted((man / f"man{s}").iterdir()):
            if not f.is_file():
                continue  # a broken symlink
            raw = read_man(f).decode("utf-8", errors="replace")
            name = f.name[:-3] if f.name.endswith(".gz") else f.name
            target = so_target(raw)
            text = man_text(raw)
            resolved = text
            if target:
                t = man / target
                t = t if t.exists() else Path(str(t) + ".gz")
                if t.is_file():
                    resolved = man_text(read_man(t).decode("utf-8", errors="replace"))
            kind = "so-redirect" if target else ("symlink" if f.is_symlink() else "page")
            rows.append({"id": f"man{s}/{name}", "label": name, "section": f"man{s}",
                         "package": owners.get(str(f)) or owners.get(os.path.realpath(f), "(unowned)"),
                         "bytes": len(raw.encode("utf-8")), "kind": kind})
            raw_docs.append(WORD.findall(text.lower()))
            resolved_docs.append(WORD.findall(resolved.lower()))
    ids = [r["id"] for r in rows]
    vecs = hashed_tfidf(raw_docs, 32, salt="man:")
    rvecs = hashed_tfidf(resolved_docs, 32, salt="man:")
    cols = ["id", "label", "section", "package", "bytes", "kind"]
    write_csv(folder / "pages.csv", cols, [[r[c] for c in cols] for r in rows])
    write_vectors(folder / "vectors.tsv", ids, vecs)
    write_vectors(folder / "vectors-resolved.tsv", ids, rvecs)
    fields = {"weight": "bytes", "groups": ["section", "package"]}
    about = [
        f"English man pages of sections {', '.join(sections)} (symlinked pages read through",
        "the link: exact duplicate vectors), grouped by section and owning package,",
        "sized by uncompressed bytes, similar by the cosine of 32-d hashed TF-IDF",
        "vectors of their text (only the vectors are stored).",
    ]
    write_config(folder, about + [
        "`.so` redirect pages have no text of their own; here they take their",
        "target's vector (vectors-resolved.tsv). zero-vectors.yaml keeps the zeros.",
    ], [{
        "name": "man-pages",
        "title": "Man pages by size; neighbours have similar text",
        "format": "embedding-matrix",
        "files": {"nodes": "pages.csv", "vectors": "vectors-resolved.tsv"},
        "fields": fields,
    }])
    write_config(folder, about + [
        "`.so` redirect pages have no text of their own, so a naive pipeline gives",
        "them zero vectors (vectors.tsv), which embedding-matrix rejects today.",
    ], [{
        "name": "man-pages-zero",
        "title": "Man pages by size (zero vectors kept); neighbours have similar text",
        "format": "embedding-matrix",
        "files": {"nodes": "pages.csv", "vectors": "vectors.tsv"},
        "fields": fields,
    }], filename="zero-vectors.yaml")
    facts = grouped_facts(rows, ["section", "package"], "bytes")
    facts.update({"source": f"/usr/share/man/man{{{','.join(sections)}}}", "format": "embedding-matrix",
                  "so_redirect_pages": sum(1 for r in rows if r["kind"] == "so-redirect"),
                  "symlinked_pages": sum(1 for r in rows if r["kind"] == "symlink")})
    facts.update(vector_facts(ids, vecs))
    facts["resolved"] = vector_facts(ids, rvecs)
    return facts


# ---------------------------------------------------------------- /usr/bin


def trigram_vector(name, dim):
    """L2-normalised counts of the name's character trigrams (^ and $ padded)."""
    s = f"^{name}$"
    v = [0.0] * dim
    for i in range(len(s) - 2):
        v[zlib.crc32(("tri:" + s[i:i + 3]).encode("utf-8")) % dim] += 1.0
    norm = math.sqrt(sum(x * x for x in v))
    return [x / norm for x in v]


def make_usr_bin(folder, bindir=Path("/usr/bin")):
    """usr-bin: one flat group of every /usr/bin entry, by size, name trigrams."""
    rows = []
    for f in sorted(bindir.iterdir()):
        try:
            st = f.stat()
        except OSError:
            continue  # a broken symlink
        if not f.is_file():
            continue
        with open(f, "rb") as h:
            head = h.read(4)
        kind = "elf" if head == b"\x7fELF" else ("script" if head[:2] == b"#!" else "other")
        rows.append({"id": f.name, "label": f.name, "bytes": st.st_size, "kind": kind,
                     "symlink": "yes" if f.is_symlink() else "no"})
    vecs = [trigram_vector(r["id"], 32) for r in rows]
    cols = ["id", "label", "bytes", "kind", "symlink"]
    write_csv(folder / "programs.csv", cols, [[r[c] for c in cols] for r in rows])
    # Two spellings of the same vectors: the header's first field `program` and
    # `id`. There is a program called `id`, so with the `id` header the header row's
    # id names a node, and embedding-matrix takes the header for data.
    write_vectors(folder / "vectors.tsv", [r["id"] for r in rows], vecs, id_header="program")
    write_vectors(folder / "vectors-id-header.tsv", [r["id"] for r in rows], vecs)
    about = [
        f"Every program in {bindir} (symlinks followed: their size is the target's),",
        "flat under one root, sized by bytes, similar by the cosine of 32-d hashed",
        "character-trigram counts of their names.",
    ]
    dataset = {
        "name": "usr-bin",
        "title": "/usr/bin by size; neighbours have similar names",
        "format": "embedding-matrix",
        "files": {"nodes": "programs.csv", "vectors": "vectors.tsv"},
        "fields": {"weight": "bytes"},
    }
    write_config(folder, about, [dataset])
    write_config(folder, about + [
        "The vectors' header starts with `id`, and /usr/bin/id is a node: the",
        "header row is then read as data (an error today).",
    ], [dict(dataset, name="usr-bin-id-header", files={"nodes": "programs.csv", "vectors": "vectors-id-header.tsv"})],
        filename="id-header.yaml")
    facts = tree_facts({r["id"]: "root" for r in rows}, {r["id"]: r["bytes"] for r in rows}, {"root": None})
    facts.update({"source": str(bindir), "format": "embedding-matrix"})
    facts.update(vector_facts([r["id"] for r in rows], vecs))
    return facts


# ---------------------------------------------------------------- main


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="target/realdata", help="output folder (default target/realdata)")
    ap.add_argument("--only", default="", help="comma-separated dataset names")
    ap.add_argument("--list", action="store_true", help="print the dataset names and exit")
    ap.add_argument("--stdlib", default=sysconfig.get_paths()["stdlib"],
                    help="Python standard library folder (default: the running interpreter's)")
    ap.add_argument("--registry", default=str(Path.home() / ".cargo/registry/src"),
                    help="Cargo registry source folder (default ~/.cargo/registry/src)")
    args = ap.parse_args()
    makers = {
        "debian-packages": lambda d: make_debian_packages(d),
        "python-stdlib": lambda d: make_python_stdlib(d, Path(args.stdlib)),
        "rust-crates": lambda d: make_rust_crates(d, Path(args.registry)),
        "copyright-docs": lambda d: make_copyright_docs(d),
        "man-pages": lambda d: make_man_pages(d),
        "usr-bin": lambda d: make_usr_bin(d),
    }
    if args.list:
        print("\n".join(makers))
        return 0
    names = [n for n in args.only.split(",") if n] or list(makers)
    unknown = [n for n in names if n not in makers]
    if unknown:
        ap.error(f"unknown dataset(s): {', '.join(unknown)}; --list names them")
    out = Path(args.out)
    for name in names:
        folder = out / name
        folder.mkdir(parents=True, exist_ok=True)
        facts = makers[name](folder)
        (folder / "shape.json").write_text(json.dumps(facts, indent=2, sort_keys=True) + "\n", encoding="utf-8")
        size = sum(f.stat().st_size for f in folder.iterdir() if f.is_file())
        print(f"{name}: {facts['leaves']} leaves, {facts['groups_top_level']} top-level groups, "
              f"largest sibling group {facts['largest_sibling_group']}, weight ratio 1:{facts['weight_ratio']:g}, "
              f"{size / 1e6:.2f} MB -> {folder}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
