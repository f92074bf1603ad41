//! What the PNG encoder's settings cost on a real picture (issue 32, item 2:
//! "encode the PNG at a speed fit for watching"): the picture of an SVG
//! output rendered once by nptreemap's own PNG path, decoded back to RGBA,
//! then encoded with each compression level and row filter of the png
//! crate, `--repeat` times each: median milliseconds and bytes. Not a test;
//! its table goes in BENCHMARKS.md. Owns only this example.
//!
//! ```sh
//! cargo run --release --example png_encoder -- out/headers.svg
//! cargo run --release --example png_encoder -- --repeat 9 --scale 2 out/map.svg
//! ```

use std::time::Instant;

use png::{Compression, Filter};

/// The settings compared: each level with the filter it chooses itself,
/// then the fastest level with each filter.
const SETTINGS: [(&str, Compression, Option<Filter>); 9] = [
    ("NoCompression", Compression::NoCompression, None),
    ("Fastest (now)", Compression::Fastest, None),
    ("Fast", Compression::Fast, None),
    (
        "Balanced (the crate's default)",
        Compression::Balanced,
        None,
    ),
    ("High", Compression::High, None),
    (
        "Fastest, filter None",
        Compression::Fastest,
        Some(Filter::NoFilter),
    ),
    (
        "Fastest, filter Sub",
        Compression::Fastest,
        Some(Filter::Sub),
    ),
    ("Fastest, filter Up", Compression::Fastest, Some(Filter::Up)),
    (
        "Fastest, filter Adaptive",
        Compression::Fastest,
        Some(Filter::Adaptive),
    ),
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut repeat, mut scale, mut svg) = (5usize, 1.0f64, None);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--repeat" => repeat = args.next().ok_or("--repeat N")?.parse()?,
            "--scale" => scale = args.next().ok_or("--scale S")?.parse()?,
            path => svg = Some(path.to_owned()),
        }
    }
    let svg = svg.ok_or("usage: png_encoder [--repeat N] [--scale S] FILE.svg")?;
    let text = std::fs::read_to_string(&svg)?;
    let t = Instant::now();
    let ours = nptreemap::render::png::png(&text, scale)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    let decoder = png::Decoder::new(std::io::Cursor::new(&ours));
    let mut reader = decoder.read_info()?;
    let mut rgba = vec![0; reader.output_buffer_size().ok_or("image too large")?];
    let info = reader.next_frame(&mut rgba)?;
    rgba.truncate(info.buffer_size());
    println!(
        "{svg}: {} x {} px, rendered and encoded by nptreemap in {render_ms:.1} ms ({} bytes)\n",
        info.width,
        info.height,
        ours.len()
    );
    println!("| encoder setting | median ms | bytes | ms / Fastest | bytes / Fastest |");
    println!("|---|---:|---:|---:|---:|");
    let mut rows = Vec::new();
    for (name, level, filter) in SETTINGS {
        let mut times = Vec::with_capacity(repeat);
        let mut len = 0;
        for _ in 0..repeat.max(1) {
            let t = Instant::now();
            let mut out = Vec::new();
            let mut encoder = png::Encoder::new(&mut out, info.width, info.height);
            encoder.set_color(png::ColorType::Rgba);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_compression(level);
            if let Some(filter) = filter {
                encoder.set_filter(filter);
            }
            let mut writer = encoder.write_header()?;
            writer.write_image_data(&rgba)?;
            writer.finish()?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
            len = out.len();
        }
        times.sort_by(f64::total_cmp);
        rows.push((name, times[times.len() / 2], len));
    }
    let (_, base_ms, base_len) = rows[1];
    for (name, ms, len) in rows {
        println!(
            "| {name} | {ms:.1} | {len} | {:.2} | {:.2} |",
            ms / base_ms,
            len as f64 / base_len as f64
        );
    }
    Ok(())
}
