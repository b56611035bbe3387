//! End-to-end tests of the figure writers: files are written in both formats, SVG text carries
//! titles and labels, PNG headers carry the expected size, and bad input gives named errors.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use fistage_plot::{
    BodeSeries, ColourScale, Figure, Heatmap, Panel, PlotError, Series, SeriesStyle, XyPlot,
    write_bode, write_figure, write_heatmap, write_xy,
};

/// A fresh output directory for one test.
fn out_dir(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("fistage-plot")
        .join(test);
    // A leftover directory from an earlier run is fine; a failure shows up when writing.
    let _ = std::fs::remove_dir_all(&dir);
    let created = std::fs::create_dir_all(&dir);
    assert!(
        created.is_ok(),
        "cannot create {}: {created:?}",
        dir.display()
    );
    dir
}

fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

fn read_text(path: &Path) -> String {
    String::from_utf8(read(path)).unwrap_or_else(|e| panic!("{} is not UTF-8: {e}", path.display()))
}

/// Width and height from the IHDR chunk, after checking the PNG signature.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = read(path);
    assert!(
        bytes.len() > 24,
        "{} is too short for a PNG",
        path.display()
    );
    assert_eq!(
        &bytes[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} lacks the PNG signature",
        path.display()
    );
    assert_eq!(&bytes[12..16], b"IHDR");
    let word =
        |at: usize| u32::from_be_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    (word(16), word(20))
}

fn time(n: usize, dt: f64) -> Vec<f64> {
    (0..n).map(|i| i as f64 * dt).collect()
}

/// A three-panel stick-slip style response.
fn stage_figure(n: usize) -> Figure {
    let t = time(n, 5.0 / n as f64);
    let table: Vec<f64> = t
        .iter()
        .map(|t| 1e-6 * (1.0 - (-3.0 * t).exp() * (40.0 * t).cos()))
        .collect();
    let target: Vec<f64> = t.iter().map(|_| 1e-6).collect();
    let bearing: Vec<f64> = t
        .iter()
        .map(|t| 2e-7 * (25.0 * t).sin() * (-t).exp())
        .collect();
    let friction: Vec<f64> = t
        .iter()
        .map(|t| 0.8 * (40.0 * t).sin().signum() * (-0.5 * t).exp())
        .collect();
    Figure::new(
        "Step response of the stage",
        "time [s]",
        vec![
            Panel::new(
                "table position [m]",
                vec![
                    Series::line("table", t.clone(), table),
                    Series::line("target", t.clone(), target),
                ],
            ),
            Panel::new(
                "bearing position [m]",
                vec![Series::line("bearing", t.clone(), bearing)],
            ),
            Panel::new(
                "friction force [N]",
                vec![Series::line("friction", t, friction)],
            ),
        ],
    )
}

/// A decaying spiral in micrometre-scale units, so both axes get a common factor.
fn phase_portrait() -> XyPlot {
    let t = time(20_000, 1e-3);
    let x: Vec<f64> = t
        .iter()
        .map(|t| 1e-6 * (-0.1 * t).exp() * (3.0 * t).cos())
        .collect();
    let v: Vec<f64> = t
        .iter()
        .map(|t| -3e-6 * (-0.1 * t).exp() * (3.0 * t).sin())
        .collect();
    XyPlot::new(
        "Phase portrait",
        "position [m]",
        "velocity [m/s]",
        vec![Series::line("trajectory", x, v)],
    )
}

/// Measured points against a fitted Stribeck curve.
fn data_vs_fit() -> XyPlot {
    let v: Vec<f64> = (0..60)
        .map(|i| 1e-5 * 10_f64.powf(i as f64 / 15.0))
        .collect();
    let stribeck = |v: f64| 0.3 + 0.2 * (-(v / 1e-3).powi(2)).exp() + 40.0 * v;
    let measured: Vec<f64> = v
        .iter()
        .enumerate()
        .map(|(i, &v)| stribeck(v) * (1.0 + 0.02 * ((i * 7) % 5) as f64 - 0.04))
        .collect();
    let model: Vec<f64> = v.iter().map(|&v| stribeck(v)).collect();
    XyPlot {
        x_log: true,
        ..XyPlot::new(
            "Steady-state friction",
            "velocity [m/s]",
            "friction force [N]",
            vec![
                Series::markers("measured", v.clone(), measured),
                Series::line("LuGre fit", v, model),
            ],
        )
    }
}

fn stability_map(scale: ColourScale) -> Heatmap {
    let x: Vec<f64> = (0..40)
        .map(|i| 1e-3 * 10_f64.powf(i as f64 / 13.0))
        .collect();
    let y: Vec<f64> = (0..30).map(|j| j as f64 * 0.1).collect();
    let mut values = Vec::new();
    for (j, &yy) in y.iter().enumerate() {
        for (i, &xx) in x.iter().enumerate() {
            let value = match &scale {
                ColourScale::Categorical { .. } => ((xx.log10() + 3.0 + yy) as usize % 3) as f64,
                ColourScale::Diverging => (xx.log10() + 1.5) * (yy - 1.5),
                ColourScale::Sequential => xx.log10() * yy,
            };
            values.push(if i == 5 && j > 20 { f64::NAN } else { value });
        }
    }
    let boundary_x: Vec<f64> = (0..50)
        .map(|i| 1e-3 * 10_f64.powf(i as f64 / 15.0))
        .collect();
    let boundary_y: Vec<f64> = boundary_x.iter().map(|x| 1.5 + 0.5 * x.log10()).collect();
    Heatmap {
        value_label: "growth rate [1/s]".into(),
        x_log: true,
        overlay: vec![Series::line("stability boundary", boundary_x, boundary_y)],
        ..Heatmap::new(
            "Stability map",
            "stiffness ratio [-]",
            "damping [N s/m]",
            x,
            y,
            values,
            scale,
        )
    }
}

fn bode_series() -> (Vec<f64>, Vec<BodeSeries>) {
    let f: Vec<f64> = (0..300).map(|i| 10_f64.powf(i as f64 / 100.0)).collect();
    let response = |fr: f64, zeta: f64| -> (Vec<f64>, Vec<f64>) {
        f.iter()
            .map(|&w| {
                let r = w / fr;
                let (re, im) = (1.0 - r * r, 2.0 * zeta * r);
                (1.0 / re.hypot(im), -im.atan2(re).to_degrees())
            })
            .unzip()
    };
    let (model_mag, model_phase) = response(50.0, 0.05);
    let (data_mag, data_phase) = response(52.0, 0.07);
    let data = BodeSeries::new("measured", data_mag, Some(data_phase), SeriesStyle::Markers);
    let model = BodeSeries::new("model", model_mag, Some(model_phase), SeriesStyle::Line);
    (f, vec![data, model])
}

#[test]
fn figure_svg_holds_title_and_axis_labels_as_text() {
    let path = out_dir("figure_svg").join("step.svg");
    write_figure(&stage_figure(2_000), &path).expect("figure written");
    let svg = read_text(&path);
    assert!(svg.starts_with("<svg"));
    for text in [
        "Step response of the stage",
        "time [s]",
        "table position [m]",
        "bearing position [m]",
        "friction force [N]",
        "target",
    ] {
        assert!(svg.contains(text), "SVG lacks {text:?}");
    }
    // Micrometre-scale positions are labelled with a common factor.
    assert!(svg.contains("\u{d7}10\u{207b}\u{2076}"));
}

#[test]
fn figure_png_has_the_expected_size() {
    let path = out_dir("figure_png").join("step.png");
    write_figure(&stage_figure(2_000), &path).expect("figure written");
    assert_eq!(png_size(&path), (1000, 56 + 3 * 300 + 64));
}

#[test]
fn extension_case_is_ignored() {
    let path = out_dir("extension_case").join("STEP.PNG");
    write_figure(&stage_figure(100), &path).expect("figure written");
    png_size(&path);
}

#[test]
fn xy_plot_in_both_formats() {
    let dir = out_dir("xy");
    let mut plot = phase_portrait();
    write_xy(&plot, &dir.join("phase.png")).expect("png written");
    assert_eq!(png_size(&dir.join("phase.png")), (1000, 780));
    plot.equal_aspect = true;
    write_xy(&plot, &dir.join("phase_equal.png")).expect("png written");
    write_xy(&plot, &dir.join("phase.svg")).expect("svg written");
    let svg = read_text(&dir.join("phase.svg"));
    for text in [
        "Phase portrait",
        "position [m]",
        "velocity [m/s]",
        "\u{d7}10\u{207b}\u{2076}",
    ] {
        assert!(svg.contains(text), "SVG lacks {text:?}");
    }
    // A single series needs no legend.
    assert!(!svg.contains("trajectory"));

    let fit = data_vs_fit();
    write_xy(&fit, &dir.join("fit.png")).expect("png written");
    write_xy(&fit, &dir.join("fit.svg")).expect("svg written");
    let svg = read_text(&dir.join("fit.svg"));
    assert!(svg.contains("measured") && svg.contains("LuGre fit"));
    assert!(svg.contains("<circle"), "markers are drawn");
}

#[test]
fn heatmaps_of_every_colour_scale() {
    let dir = out_dir("heatmap");
    let labels = vec![
        "stable".to_string(),
        "oscillating".into(),
        "bistable".into(),
    ];
    let scales = [
        ("sequential", ColourScale::Sequential),
        ("diverging", ColourScale::Diverging),
        ("categorical", ColourScale::Categorical { labels }),
    ];
    for (name, scale) in scales {
        let heatmap = stability_map(scale);
        let png = dir.join(format!("{name}.png"));
        write_heatmap(&heatmap, &png).expect("png written");
        assert_eq!(png_size(&png), (1000, 800));
        let svg_path = dir.join(format!("{name}.svg"));
        write_heatmap(&heatmap, &svg_path).expect("svg written");
        let svg = read_text(&svg_path);
        for text in [
            "Stability map",
            "stiffness ratio [-]",
            "damping [N s/m]",
            "not computed",
        ] {
            assert!(svg.contains(text), "{name} SVG lacks {text:?}");
        }
        // The NaN cells are grey.
        assert!(svg.contains("#AFAFAF"), "{name} SVG has no grey cells");
    }
    let categorical = read_text(&dir.join("categorical.svg"));
    assert!(categorical.contains("oscillating") && categorical.contains("bistable"));
    assert!(read_text(&dir.join("sequential.svg")).contains("growth rate [1/s]"));
}

#[test]
fn bode_plot_in_both_formats() {
    let dir = out_dir("bode");
    let (f, series) = bode_series();
    write_bode("Frequency response", &f, &series, &dir.join("bode.png")).expect("png written");
    assert_eq!(png_size(&dir.join("bode.png")), (1000, 56 + 2 * 300 + 64));
    write_bode("Frequency response", &f, &series, &dir.join("bode.svg")).expect("svg written");
    let svg = read_text(&dir.join("bode.svg"));
    for text in [
        "Frequency response",
        "frequency [Hz]",
        "magnitude [dB]",
        "phase [\u{b0}]",
        "measured",
    ] {
        assert!(svg.contains(text), "SVG lacks {text:?}");
    }
    // Decade labels of the log frequency axis.
    assert!(
        svg.contains("\n10\n") && svg.contains("\n100\n"),
        "missing decade labels"
    );
}

#[test]
fn long_series_stay_small_and_fast() {
    let dir = out_dir("long");
    let n = 500_000;
    let t = time(n, 1e-5);
    let y: Vec<f64> = t
        .iter()
        .map(|t| (-t / 2.0).exp() * (t * 2_000.0).sin())
        .collect();
    let figure = Figure::new(
        "Long record",
        "time [s]",
        vec![Panel::new("x [m]", vec![Series::line("x", t, y)])],
    );
    let path = dir.join("long.svg");
    let start = Instant::now();
    write_figure(&figure, &path).expect("svg written");
    let elapsed = start.elapsed();
    let size = read(&path).len();
    assert!(size < 300_000, "SVG of a 500k-point series is {size} bytes");
    // Generous bound: the test profile is optimised, a release build is well under a second.
    assert!(elapsed < Duration::from_secs(3), "writing took {elapsed:?}");
    write_figure(&figure, &dir.join("long.png")).expect("png written");

    // A phase portrait circling thousands of times stays bounded too.
    let (x, v): (Vec<f64>, Vec<f64>) = (0..n)
        .map(|i| {
            let t = i as f64 * 0.02;
            let r = 1.0 - t / 20_000.0;
            (r * t.cos(), 2.0 * r * t.sin())
        })
        .unzip();
    let portrait = XyPlot::new(
        "Limit cycle",
        "x [m]",
        "v [m/s]",
        vec![Series::line("orbit", x, v)],
    );
    let path = dir.join("portrait.svg");
    let start = Instant::now();
    write_xy(&portrait, &path).expect("svg written");
    let elapsed = start.elapsed();
    let size = read(&path).len();
    assert!(
        size < 2_000_000,
        "SVG of a 500k-point portrait is {size} bytes"
    );
    assert!(elapsed < Duration::from_secs(3), "writing took {elapsed:?}");
    write_xy(&portrait, &dir.join("portrait.png")).expect("png written");
}

#[test]
fn nan_and_empty_data_give_a_no_data_figure() {
    let dir = out_dir("no_data");
    let t = time(100, 0.01);
    let figure = Figure::new(
        "Partly computed",
        "time [s]",
        vec![
            Panel::new(
                "all NaN [m]",
                vec![Series::line("nan", t.clone(), vec![f64::NAN; 100])],
            ),
            Panel::new(
                "empty [N]",
                vec![Series::line("empty", Vec::<f64>::new(), Vec::<f64>::new())],
            ),
            Panel::new(
                "gappy [m]",
                vec![Series::line(
                    "gappy",
                    t.clone(),
                    t.iter()
                        .map(|t| {
                            if (t * 10.0) as i32 % 2 == 0 {
                                *t
                            } else {
                                f64::NAN
                            }
                        })
                        .collect::<Vec<_>>(),
                )],
            ),
        ],
    );
    let path = dir.join("nan.svg");
    write_figure(&figure, &path).expect("svg written");
    let svg = read_text(&path);
    assert_eq!(
        svg.matches("\nno data\n").count(),
        2,
        "two panels have no data"
    );
    write_figure(&figure, &dir.join("nan.png")).expect("png written");

    let empty = Figure::new("Nothing yet", "time [s]", Vec::new());
    write_figure(&empty, &dir.join("empty.svg")).expect("empty figure written");
    assert!(read_text(&dir.join("empty.svg")).contains("no data"));
    write_xy(
        &XyPlot::new("Empty", "x", "y", Vec::new()),
        &dir.join("xy.svg"),
    )
    .expect("empty xy");
    assert!(read_text(&dir.join("xy.svg")).contains("no data"));
    let heatmap = Heatmap::new(
        "Empty",
        "x",
        "y",
        Vec::new(),
        Vec::new(),
        Vec::new(),
        ColourScale::Sequential,
    );
    write_heatmap(&heatmap, &dir.join("heatmap.png")).expect("empty heatmap");
}

#[test]
fn constant_data_get_labelled_ticks() {
    let dir = out_dir("constant");
    let t = time(50, 0.1);
    let figure = Figure::new(
        "Constant",
        "time [s]",
        vec![Panel::new(
            "force [N]",
            vec![Series::line("f", t.clone(), vec![2.5; 50])],
        )],
    );
    let path = dir.join("constant.svg");
    write_figure(&figure, &path).expect("svg written");
    let svg = read_text(&path);
    // The range is widened around the value, so ticks on both sides of 2.5 are labelled.
    let labels: Vec<f64> = svg.lines().filter_map(|line| line.parse().ok()).collect();
    assert!(
        labels.iter().any(|&v| v < 2.5) && labels.iter().any(|&v| v > 2.5 && v < 3.0),
        "{labels:?}"
    );
    assert!(svg.contains("<polyline") && !svg.contains("no data"));
}

#[test]
fn log_axes_skip_non_positive_values() {
    let dir = out_dir("log");
    let x = vec![-1.0, 0.0, 1.0, 10.0, 100.0];
    let y = vec![1.0, 1.0, 0.5, 0.0, 2.0];
    let plot = XyPlot {
        x_log: true,
        y_log: true,
        ..XyPlot::new(
            "Log",
            "f [Hz]",
            "gain [-]",
            vec![Series::line_and_markers("g", x, y)],
        )
    };
    write_xy(&plot, &dir.join("log.svg")).expect("svg written");
    write_xy(&plot, &dir.join("log.png")).expect("png written");
}

#[test]
fn length_mismatch_is_an_error_naming_the_series() {
    let dir = out_dir("mismatch");
    let path = dir.join("bad.svg");
    let mut figure = stage_figure(10);
    figure.panels[1]
        .series
        .push(Series::line("bearing velocity", vec![0.0, 1.0], vec![0.0]));
    let error = write_figure(&figure, &path).expect_err("mismatch detected");
    assert!(
        matches!(error, PlotError::LengthMismatch { ref label, x_len: 2, y_len: 1, .. } if label == "bearing velocity")
    );
    let message = error.to_string();
    assert!(
        message.contains("bearing velocity") && message.contains("bad.svg"),
        "{message}"
    );
    assert!(!path.exists(), "no file is written on error");

    let xy = XyPlot::new(
        "t",
        "x",
        "y",
        vec![Series::markers("fit", vec![1.0], Vec::<f64>::new())],
    );
    let message = write_xy(&xy, &path)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(message.contains("fit"), "{message}");

    let (f, mut series) = bode_series();
    series[1].magnitude.pop();
    let message = write_bode("b", &f, &series, &path)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(message.contains("model (magnitude)"), "{message}");

    let heatmap = Heatmap::new(
        "h",
        "x",
        "y",
        vec![1.0, 2.0],
        vec![1.0, 2.0],
        vec![0.0; 3],
        ColourScale::Sequential,
    );
    let error = write_heatmap(&heatmap, &path).expect_err("shape mismatch detected");
    assert!(
        matches!(
            error,
            PlotError::HeatmapShape {
                expected: 4,
                len: 3,
                ..
            }
        ),
        "{error}"
    );
}

#[test]
fn unsupported_extension_is_an_error_naming_the_path() {
    let dir = out_dir("extension");
    for name in ["figure.pdf", "figure"] {
        let path = dir.join(name);
        let error = write_figure(&stage_figure(10), &path).expect_err("extension rejected");
        assert!(matches!(error, PlotError::UnsupportedExtension { .. }));
        assert!(
            error.to_string().contains(&path.display().to_string()),
            "{error}"
        );
        assert!(!path.exists());
    }
    let error = write_xy(&data_vs_fit(), &dir.join("phase.jpg")).expect_err("extension rejected");
    assert!(error.to_string().contains("phase.jpg"));
}

#[test]
fn unwritable_path_is_an_io_error_naming_the_path() {
    let path = out_dir("io").join("missing-directory").join("figure.svg");
    let error = write_figure(&stage_figure(10), &path).expect_err("write fails");
    assert!(matches!(error, PlotError::Io { .. }), "{error}");
    assert!(error.to_string().contains("missing-directory"), "{error}");
}
