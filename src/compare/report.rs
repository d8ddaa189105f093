//! The comparison as a Markdown table and as an error-against-time plot (SVG: text needs no font
//! files, and any browser or image viewer shows it). Text that comes from outside (the scene's
//! name, run names) is escaped in the SVG.

use std::borrow::Cow;
use std::fmt::Write;

use super::{CompareReport, RunReport};
use crate::math::Real;

/// One row per run: cost, visible and geometric error (means over the compared frames); then,
/// with a floor, every mode's multiple of the floor and verdict per measure.
pub fn markdown(r: &CompareReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# {}: {} frames, error against `{}` ({}×{} px)\n",
        r.scene,
        r.frames,
        r.reference.dir.display(),
        r.image[0],
        r.image[1]
    );
    let _ = writeln!(
        s,
        "| run | wall s | mean faces | normal ° shading / flat | silhouette | depth | distance mean / RMS / p95 / max (mm) | visible part mean / p95 (mm) |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|");
    let _ =
        writeln!(s, "| reference | {:.2} | {:.0} | – | – | – | – | – |", r.reference.wall_s, r.reference.mean_faces);
    for run in r.floors.iter().chain(&r.modes) {
        let Some(e) = &run.errors else { continue };
        let (g, v) = (&e.geometric, &e.geometric_visible);
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.0} | {:.2} / {:.2} | {:.4} | {:.4} | {:.2} / {:.2} / {:.2} / {:.2} | {:.2} / {:.2} |",
            run.name,
            run.wall_s,
            run.mean_faces,
            e.visible.normal_deg,
            e.visible.normal_flat_deg,
            e.visible.silhouette,
            e.visible.depth,
            1e3 * g.mean,
            1e3 * g.rms,
            1e3 * g.p95,
            1e3 * g.max,
            1e3 * v.mean,
            1e3 * v.p95
        );
    }
    if let Some(band) = &r.floor_band {
        let _ = writeln!(
            s,
            "\nAgainst the chaos floor ({} runs, {} frames): the floor's mean ± standard deviation of the runs' \
             frame-averaged errors; per mode, the multiple of the floor mean, then `within` (≤ mean + 2σ) or how \
             many σ above, and in how many frames the error exceeds that frame's mean + 2σ.\n",
            band.runs,
            band.frames.len()
        );
        let _ = writeln!(s, "| run | {} |", band.measures.iter().map(|m| m.measure).collect::<Vec<_>>().join(" | "));
        let _ = writeln!(s, "|---|{}", "---:|".repeat(band.measures.len()));
        let cells: Vec<String> = band.measures.iter().map(|m| format!("{} ± {}", num(m.mean), num(m.std))).collect();
        let _ = writeln!(s, "| floor | {} |", cells.join(" | "));
        for run in &r.modes {
            let Some(v) = &run.verdicts else { continue };
            let cells: Vec<String> = v
                .iter()
                .map(|v| {
                    let verdict = if v.within { "within".to_string() } else { format!("+{:.1}σ", v.sigmas) };
                    format!("{:.1}× {verdict} ({}/{})", v.multiple, v.frames_above, v.frames)
                })
                .collect();
            let _ = writeln!(s, "| {} | {} |", run.name, cells.join(" | "));
        }
    }
    s
}

/// Four significant digits, whatever the scale (degrees, ratios, metres).
fn num(x: Real) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = (3 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.digits$}")
}

/// Mean normal error (°) against wall time (s, logarithmic) for every measured run, the chaos
/// floor as a dashed line.
pub fn svg_plot(r: &CompareReport) -> String {
    let (w, h, m) = (640.0, 400.0, 60.0);
    let points: Vec<(&RunReport, Real, Real)> = r
        .modes
        .iter()
        .filter_map(|run| run.errors.as_ref().map(|e| (run, run.wall_s.max(1e-3), e.visible.normal_deg)))
        .collect();
    let band = r.floor_band.as_ref().and_then(|b| b.measures.iter().find(|m| m.measure == "normal_deg"));
    let times = points.iter().map(|p| p.1).chain([r.reference.wall_s.max(1e-3)]);
    let (t0, t1) = times.fold((Real::INFINITY, 0.0 as Real), |(a, b), t| (a.min(t), b.max(t)));
    let (lt0, lt1) = ((t0 / 2.0).log10(), (t1 * 2.0).log10());
    let band_top = band.map_or(0.0, |b| b.mean + 2.0 * b.std);
    let e1 = points.iter().map(|p| p.2).fold(band_top, Real::max).max(1e-6) * 1.2;
    let x = |t: Real| m + (t.max(1e-3).log10() - lt0) / (lt1 - lt0) * (w - 2.0 * m);
    let y = |e: Real| h - m - e / e1 * (h - 2.0 * m);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(s, r#"<path d="M{m} {m} V{} H{}" stroke="black" fill="none"/>"#, h - m, w - m);
    let _ =
        writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle">wall time (s, log scale)</text>"#, w / 2.0, h - 15.0);
    let _ = writeln!(
        s,
        r#"<text x="15" y="{}" transform="rotate(-90 15 {})" text-anchor="middle">mean normal error (°)</text>"#,
        h / 2.0,
        h / 2.0
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="25" text-anchor="middle">{}: error against run time, {} frames</text>"#,
        w / 2.0,
        xml_escape(&r.scene),
        r.frames
    );
    for k in (lt0.ceil() as i32)..=(lt1.floor() as i32) {
        let t = 10f64.powi(k);
        let _ = writeln!(s, r#"<text x="{:.1}" y="{}" text-anchor="middle">{t}</text>"#, x(t), h - m + 16.0);
    }
    let _ = writeln!(s, r#"<text x="{}" y="{:.1}" text-anchor="end">{:.2}</text>"#, m - 5.0, y(e1) + 4.0, e1);
    let _ = writeln!(s, r#"<text x="{}" y="{:.1}" text-anchor="end">0</text>"#, m - 5.0, y(0.0) + 4.0);
    if let Some(b) = band {
        // The floor band: mean (dashed) to mean + 2σ (shaded).
        let (ym, yt) = (y(b.mean), y(b.mean + 2.0 * b.std));
        let _ = writeln!(
            s,
            r#"<rect x="{m}" y="{yt:.1}" width="{}" height="{:.1}" fill="gray" fill-opacity="0.2"/>"#,
            w - 2.0 * m,
            ym - yt
        );
        let _ = writeln!(s, r#"<path d="M{m} {ym:.1} H{}" stroke="gray" stroke-dasharray="6 4"/>"#, w - m);
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{:.1}" text-anchor="end" fill="gray">chaos floor (mean to mean + 2σ)</text>"#,
            w - m,
            yt - 4.0
        );
    }
    let xr = x(r.reference.wall_s);
    let _ = writeln!(s, r#"<circle cx="{xr:.1}" cy="{:.1}" r="5" fill="black"/>"#, y(0.0));
    let _ = writeln!(s, r#"<text x="{xr:.1}" y="{:.1}" text-anchor="middle">reference</text>"#, y(0.0) - 10.0);
    for (run, t, e) in &points {
        let (cx, cy) = (x(*t), y(*e));
        let _ = writeln!(s, r#"<circle cx="{cx:.1}" cy="{cy:.1}" r="5" fill="steelblue"/>"#);
        let _ = writeln!(
            s,
            r#"<text x="{cx:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            cy - 10.0,
            xml_escape(&run.name)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// One measure (`MEASURES[measure]`) per compared frame against the frame's time, a line per
/// mode, with the floor band (per frame mean to mean + 2σ, shaded) when there is one.
pub fn svg_curves(r: &CompareReport, measure: usize) -> String {
    let m = &super::MEASURES[measure];
    let (w, h, pad) = (640.0, 400.0, 60.0);
    let curves: Vec<(&str, Vec<(Real, Real)>)> = r
        .modes
        .iter()
        .filter_map(|run| {
            let e = run.errors.as_ref()?;
            Some((run.name.as_str(), e.per_frame.iter().map(|f| (f.time, (m.get)(f))).collect()))
        })
        .collect();
    let band = r.floor_band.as_ref().map(|b| (b, &b.measures[measure]));
    let times = |b: &super::FloorBand| -> Vec<Real> {
        let first = r.floors.iter().find_map(|f| f.errors.as_ref());
        b.frames
            .iter()
            .map(|&fr| first.and_then(|e| e.per_frame.iter().find(|p| p.frame == fr)).map_or(0.0, |p| p.time))
            .collect()
    };
    let all = curves.iter().flat_map(|c| c.1.iter().copied());
    let (t1, mut e1) = all.fold((0.0 as Real, 0.0 as Real), |(t, e), p| (t.max(p.0), e.max(p.1)));
    if let Some((_, mb)) = band {
        e1 = mb.per_frame_mean.iter().zip(&mb.per_frame_std).map(|(a, b)| a + 2.0 * b).fold(e1, Real::max);
    }
    let (t1, e1) = (t1.max(1e-6), if e1.is_finite() { e1.max(1e-12) * 1.1 } else { 1.0 });
    let x = |t: Real| pad + t / t1 * (w - 2.0 * pad);
    let y = |e: Real| h - pad - e.min(e1) / e1 * (h - 2.0 * pad);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(s, r#"<path d="M{pad} {pad} V{} H{}" stroke="black" fill="none"/>"#, h - pad, w - pad);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="25" text-anchor="middle">{}: {} per frame</text>"#,
        w / 2.0,
        xml_escape(&r.scene),
        m.name
    );
    let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle">time (s)</text>"#, w / 2.0, h - 15.0);
    let _ = writeln!(s, r#"<text x="{}" y="{}" text-anchor="middle">{t1:.2}</text>"#, x(t1), h - pad + 16.0);
    let _ = writeln!(s, r#"<text x="{}" y="{:.1}" text-anchor="end">{}</text>"#, pad - 5.0, y(e1) + 4.0, num(e1));
    let _ = writeln!(s, r#"<text x="{}" y="{:.1}" text-anchor="end">0</text>"#, pad - 5.0, y(0.0) + 4.0);
    if let Some((b, mb)) = band {
        let ts = times(b);
        let top = ts.iter().zip(mb.per_frame_mean.iter().zip(&mb.per_frame_std)).map(|(&t, (a, d))| (t, a + 2.0 * d));
        let bottom = ts.iter().zip(&mb.per_frame_mean).rev().map(|(&t, &a)| (t, a));
        let pts: Vec<String> = top.chain(bottom).map(|(t, e)| format!("{:.1},{:.1}", x(t), y(e))).collect();
        let _ = writeln!(s, r#"<polygon points="{}" fill="gray" fill-opacity="0.3"/>"#, pts.join(" "));
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="end" fill="gray">chaos floor band</text>"#,
            w - pad,
            pad - 5.0
        );
    }
    const COLOURS: [&str; 4] = ["steelblue", "darkorange", "seagreen", "crimson"];
    for (k, (name, pts)) in curves.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let p: Vec<String> = pts.iter().map(|&(t, e)| format!("{:.1},{:.1}", x(t), y(e))).collect();
        let _ = writeln!(s, r#"<polyline points="{}" fill="none" stroke="{colour}"/>"#, p.join(" "));
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" fill="{colour}">{}</text>"#,
            pad + 10.0,
            pad + 15.0 * (k + 1) as Real,
            xml_escape(name)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// `text` with the five characters XML reserves replaced by their entities (XML 1.0 §2.4), for
/// element content and attribute values alike.
fn xml_escape(text: &str) -> Cow<'_, str> {
    if !text.contains(['&', '<', '>', '"', '\'']) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;
    use crate::compare::Errors;

    fn run(name: &str, wall_s: Real, normal_deg: Real) -> RunReport {
        let mut errors = Errors::default();
        errors.visible.normal_deg = normal_deg;
        let mut f = crate::compare::FrameErrors { frame: 1, ..Default::default() };
        f.visible.normal_deg = normal_deg;
        errors.per_frame = vec![f];
        RunReport {
            name: name.into(),
            dir: PathBuf::from(name),
            wall_s,
            mean_faces: 100.0,
            errors: Some(errors),
            verdicts: None,
        }
    }

    #[test]
    fn escapes_the_five_reserved_characters() {
        assert_eq!(xml_escape("plain name"), "plain name");
        assert_eq!(xml_escape(r#"a<b & "c" > 'd'"#), "a&lt;b &amp; &quot;c&quot; &gt; &apos;d&apos;");
    }

    /// A scene and a run named with XML's reserved characters give a well-formed SVG whose
    /// text reads back as the names.
    #[test]
    fn names_with_markup_give_well_formed_svg() {
        let scene = r#"a<b & "c""#;
        let report = CompareReport {
            scene: scene.into(),
            frames: 12,
            image: [320, 180],
            reference: RunReport { errors: None, ..run("reference", 30.0, 0.0) },
            floors: vec![run("floor_1", 31.0, 0.5), run("floor_2", 32.0, 0.7)],
            floor_band: None,
            modes: vec![run("adaptive", 3.0, 2.0), run("it's <odd> & \"new\"", 1.0, 4.0)],
        };
        let floors: Vec<&Errors> = report.floors.iter().filter_map(|r| r.errors.as_ref()).collect();
        let report = CompareReport { floor_band: crate::compare::floor_band(&floors), ..report };
        let svg = svg_plot(&report);
        let doc = roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{e}\n{svg}"));
        let texts: Vec<&str> = doc.descendants().filter(|n| n.has_tag_name("text")).filter_map(|n| n.text()).collect();
        assert!(texts.contains(&format!("{scene}: error against run time, 12 frames").as_str()), "{texts:?}");
        assert!(texts.contains(&"it's <odd> & \"new\""), "{texts:?}");
        assert!(texts.contains(&"adaptive") && texts.contains(&"reference"), "{texts:?}");
        assert!(texts.contains(&"chaos floor (mean to mean + 2σ)"), "{texts:?}");
        // The per-frame curves: one polyline per mode with a point per frame, and the band.
        let svg = svg_curves(&report, 0);
        let doc = roxmltree::Document::parse(&svg).unwrap_or_else(|e| panic!("{e}\n{svg}"));
        let lines: Vec<_> = doc.descendants().filter(|n| n.has_tag_name("polyline")).collect();
        assert_eq!(lines.len(), 2);
        assert!(lines.iter().all(|l| l.attribute("points").unwrap().split(' ').count() == 1));
        assert_eq!(doc.descendants().filter(|n| n.has_tag_name("polygon")).count(), 1);
    }
}
