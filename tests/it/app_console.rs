//! The console's command language (every command, quoting, errors with their column, Tab
//! completion) and the console in the viewer window inside an egui_kittest harness: the
//! backtick opens it, typed commands add a representation and move the frame, Up recalls the
//! history.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use egui::{Key, Modifiers};
use egui_kittest::Harness;
use mdsurf::app::console::{
    ConsoleCommand as C, ConsoleError, RepEdit, RepRef, complete, parse, read_script,
};
use mdsurf::app::source::helix_source;
use mdsurf::app::worker::Worker;
use mdsurf::app::{AppCore, Script, Viewer};
use mdsurf::model::ColorScheme;
use mdsurf::scene::representation::RepStyle;
use mdsurf::surface::{CpuEngine, Quality, VertexMode};

fn ok(line: &str) -> C {
    parse(line)
        .unwrap_or_else(|e| panic!("{line}: {e}"))
        .expect("a command")
}

fn column(line: &str) -> usize {
    match parse(line) {
        Err(ConsoleError::Parse { column, .. }) => column,
        other => panic!("{line}: expected a parse error, got {other:?}"),
    }
}

#[test]
fn every_command_parses() {
    assert_eq!(
        ok(r#"rep add "protein" surface"#),
        C::RepAdd {
            selection: "protein".into(),
            style: RepStyle::Surface,
            name: None
        }
    );
    assert_eq!(
        ok(r#"rep add "resname POPC" spheres as lipids"#),
        C::RepAdd {
            selection: "resname POPC".into(),
            style: RepStyle::Spheres,
            name: Some("lipids".into())
        }
    );
    assert_eq!(
        ok("rep add protein beads"),
        C::RepAdd {
            selection: "protein".into(),
            style: RepStyle::Beads,
            name: None
        }
    );
    let n = |i| RepRef::Number(i);
    assert_eq!(
        ok("rep 2 color residue-type"),
        C::Rep(n(2), RepEdit::Color(ColorScheme::ResidueType))
    );
    assert_eq!(ok("rep 2 spacing 1.5"), C::Rep(n(2), RepEdit::Spacing(1.5)));
    assert_eq!(
        ok("rep 2 cavities on"),
        C::Rep(n(2), RepEdit::Cavities(true, None))
    );
    assert_eq!(
        ok("rep 2 cavities off"),
        C::Rep(n(2), RepEdit::Cavities(false, None))
    );
    assert_eq!(
        ok("rep 2 cavities probe 1.4"),
        C::Rep(n(2), RepEdit::Cavities(true, Some(1.4)))
    );
    assert!(parse("rep 2 cavities maybe").is_err());
    assert!(parse("rep 2 cavities probe").is_err());
    assert!(parse("rep 2 cavities probe wide").is_err());
    assert_eq!(
        ok("rep 2 radius-scale 1.2"),
        C::Rep(n(2), RepEdit::RadiusScale(1.2))
    );
    assert_eq!(
        ok("rep 2 isovalue 0.5"),
        C::Rep(n(2), RepEdit::Isovalue(0.5))
    );
    assert_eq!(
        ok("rep 2 quality high"),
        C::Rep(n(2), RepEdit::Quality(Quality::High))
    );
    assert_eq!(ok("rep 1 opacity 0.4"), C::Rep(n(1), RepEdit::Opacity(0.4)));
    assert_eq!(
        ok("rep 1 vertices refined"),
        C::Rep(n(1), RepEdit::Vertices(VertexMode::Refined))
    );
    assert_eq!(
        ok("rep 1 style sticks"),
        C::Rep(n(1), RepEdit::Style(RepStyle::Sticks))
    );
    assert_eq!(
        ok(r#"rep 2 select "resname POPC""#),
        C::Rep(n(2), RepEdit::Select("resname POPC".into()))
    );
    assert_eq!(ok("rep 2 hide"), C::Rep(n(2), RepEdit::Hide));
    assert_eq!(
        ok("rep prot show"),
        C::Rep(RepRef::Name("prot".into()), RepEdit::Show)
    );
    assert_eq!(
        ok(r#"rep "my rep" delete"#),
        C::Rep(RepRef::Name("my rep".into()), RepEdit::Delete)
    );
    assert_eq!(ok("frame 10"), C::Frame(10));
    assert_eq!(ok("play"), C::Play);
    assert_eq!(ok("  pause  "), C::Pause);
    assert_eq!(ok("fit"), C::Fit(None));
    assert_eq!(
        ok(r#"fit "protein and name CA""#),
        C::Fit(Some("protein and name CA".into()))
    );
    assert_eq!(ok("view save view.toml"), C::ViewSave("view.toml".into()));
    assert_eq!(
        ok(r#"view open "my view.toml""#),
        C::ViewOpen("my view.toml".into())
    );
    assert_eq!(
        ok("screenshot out.png 3840x2160"),
        C::Screenshot("out.png".into(), Some([3840, 2160]))
    );
    assert_eq!(
        ok("screenshot out.png"),
        C::Screenshot("out.png".into(), None)
    );
    assert_eq!(
        ok(r#"select "within 5 of resname LIG""#),
        C::Select("within 5 of resname LIG".into())
    );
    assert_eq!(ok("help"), C::Help(None));
    assert_eq!(ok("help rep"), C::Help(Some("rep".into())));
    assert_eq!(parse("").unwrap(), None);
    assert_eq!(parse("   # a comment").unwrap(), None);
}

#[test]
fn errors_are_one_line_with_the_column() {
    assert_eq!(column("frobnicate 3"), 1);
    assert_eq!(column("frame ten"), 7);
    assert_eq!(column(r#"rep add "protein surface"#), 9);
    assert_eq!(column("rep 2 colour nonsense"), 14);
    assert_eq!(column("rep 2 wobble 3"), 7);
    assert_eq!(column("rep 0 hide"), 5);
    assert_eq!(column("rep 2 hide now"), 12);
    assert_eq!(column("screenshot a.png 10by20"), 18);
    assert_eq!(column("view print x"), 6);
    assert_eq!(column(r#"rep add "protein" cubes"#), 19);
    assert_eq!(column(r#"rep add "protein" surface called x"#), 27);
    // "frame" alone: the column after the line.
    assert_eq!(column("frame"), 6);
    // A selection error's column counts from the start of the line.
    let line = r#"select "name CA and (""#;
    let e = parse(line).unwrap_err();
    let ConsoleError::Parse { column, message } = &e else {
        panic!("{e:?}")
    };
    assert!(message.starts_with("selection:"), "{message}");
    assert!(*column > 8 && *column <= line.len() + 1, "{e}");
    assert!(!e.to_string().contains('\n'));
}

#[test]
fn tab_completes_words_and_names() {
    let names = vec!["protein".to_string(), "lipids".to_string()];
    assert_eq!(complete("scr", &names).as_deref(), Some("screenshot "));
    assert_eq!(complete("p", &names), None, "play and pause");
    assert_eq!(complete("pl", &names).as_deref(), Some("play "));
    assert_eq!(complete("rep li", &names).as_deref(), Some("rep lipids "));
    assert_eq!(
        complete("rep 2 rad", &names).as_deref(),
        Some("rep 2 radius-scale ")
    );
    assert_eq!(
        complete(r#"rep add "all" sp"#, &names).as_deref(),
        Some(r#"rep add "all" spheres "#)
    );
    assert_eq!(
        complete("rep 1 color resi", &names).as_deref(),
        Some("rep 1 color residue-")
    );
    assert_eq!(complete("view o", &names).as_deref(), Some("view open "));
}

#[test]
fn scripts_name_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.mdsurf");
    std::fs::write(
        &path,
        "# setup\nrep add \"all\" spheres\n\nframe 2\nframe x\n",
    )
    .unwrap();
    let e = read_script(&path).unwrap_err().to_string();
    assert!(e.contains("s.mdsurf:5: column 7"), "{e}");
    std::fs::write(&path, "# setup\nrep add \"all\" spheres\n\nframe 2\n").unwrap();
    let lines = read_script(&path).unwrap();
    assert_eq!(lines.iter().map(|l| l.0).collect::<Vec<_>>(), vec![2, 4]);
}

/// The viewer on a 20-residue helix of 15 frames, CPU engine, no GPU.
fn harness() -> Harness<'static, Viewer> {
    let mut h = Harness::builder()
        .with_size([1200.0, 800.0])
        .build_eframe(|cc| {
            let ctx = cc.egui_ctx.clone();
            let worker = Worker::spawn(
                Box::new(CpuEngine::new()),
                Box::new(move || ctx.request_repaint()),
            );
            let mut core = AppCore::new(worker);
            core.set_source(Arc::new(helix_source(20, 15)));
            Viewer::new(core, None, Script::default(), Arc::new(Mutex::new(None)))
        });
    settle(&mut h);
    h
}

fn settle(h: &mut Harness<'static, Viewer>) {
    let start = Instant::now();
    loop {
        let idle = !h.state().core().computing();
        std::thread::sleep(Duration::from_millis(10));
        h.step();
        let core = h.state().core();
        assert!(core.error.is_none(), "{:?}", core.error);
        let shown = core.shown.as_ref().map(|s| s.computed.frame);
        if idle && !core.computing() && shown == Some(core.timeline.current) {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "not settled");
    }
    h.step();
}

/// Types a line into the focused console and presses Enter.
fn enter(h: &mut Harness<'static, Viewer>, line: &str) {
    h.event(egui::Event::Text(line.to_string()));
    h.step();
    h.key_press(Key::Enter);
    h.step();
    h.step();
}

#[test]
fn commands_typed_into_the_console_change_the_app() {
    let mut h = harness();
    assert!(!h.state().console().open);
    h.key_press_modifiers(Modifiers::NONE, Key::Backtick);
    h.step();
    h.step();
    assert!(
        h.state().console().open,
        "the backtick did not open the console"
    );
    let reps = h.state().core().reps.len();
    enter(&mut h, r#"rep add "resid 1 to 5" spheres as head"#);
    let core = h.state().core();
    assert_eq!(
        core.reps.len(),
        reps + 1,
        "{:?}",
        h.state().console().output
    );
    let rep = core.reps.last().unwrap();
    assert_eq!((rep.name.as_str(), rep.style), ("head", RepStyle::Spheres));
    assert_eq!(rep.selection, "resid 1 to 5");
    enter(&mut h, "rep head opacity 0.5");
    assert_eq!(h.state().core().reps.last().unwrap().opacity, 0.5);
    enter(&mut h, "frame 3");
    settle(&mut h);
    assert_eq!(h.state().core().timeline.current, 3);
    enter(&mut h, "select \"resid 1 to 2\"");
    let out = &h.state().console().output;
    assert!(out.back().unwrap().starts_with("6 atoms"), "{out:?}");
    enter(&mut h, "frame 99");
    let out = &h.state().console().output;
    assert!(
        out.back().unwrap().starts_with("error: frame 99"),
        "{out:?}"
    );
    assert_eq!(h.state().core().timeline.current, 3);
    // Up recalls the last line; Enter runs it again.
    h.key_press(Key::ArrowUp);
    h.step();
    h.key_press(Key::ArrowUp);
    h.step();
    h.key_press(Key::Enter);
    h.step();
    h.step();
    let hist = &h.state().console().history;
    assert_eq!(hist.last().unwrap(), "select \"resid 1 to 2\"", "{hist:?}");
    enter(&mut h, "rep head delete");
    assert_eq!(h.state().core().reps.len(), reps);
}

/// `mdsurf TOP TRAJ --script FILE --quit` under Xvfb: the script adds a representation, goes to
/// frame 2 and takes a screenshot; the PNG exists and is not uniform. A bad line stops the run
/// with the file and line. Skipped without Xvfb or a wgpu adapter unless `REQUIRE_GPU=1`.
#[test]
fn script_runs_in_the_real_window() {
    let skip = |reason: &str| {
        if std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1") {
            panic!("REQUIRE_GPU=1 but {reason}");
        }
        eprintln!("note: skipping the --script window test: {reason}");
    };
    if std::process::Command::new("xvfb-run")
        .arg("--help")
        .output()
        .is_err()
    {
        return skip("xvfb-run is not installed");
    }
    if let Err(e) = mdsurf::render::HeadlessGpu::new() {
        return skip(&format!("no wgpu adapter: {e}"));
    }
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let script = dir.path().join("s.mdsurf");
    std::fs::write(
        &script,
        format!(
            "# add a representation, go to frame 2, screenshot\n\
             rep add \"resid 1 to 20\" spheres as head\n\
             frame 2\n\
             select \"name CA\"\n\
             screenshot \"{}\" 400x300\n",
            shot.display()
        ),
    )
    .unwrap();
    let demo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let run = |script: &std::path::Path| {
        let (_one_server_at_a_time, mut xvfb) = crate::xvfb_support::xvfb_run();
        xvfb.arg(env!("CARGO_BIN_EXE_mdsurf"))
            .arg(demo.join("md_1u19.gro"))
            .arg(demo.join("md_1u19.xtc"))
            .arg("--script")
            .arg(script)
            .args(["--quit", "--cpu"])
            .env("XDG_RUNTIME_DIR", dir.path())
            .output()
            .expect("run xvfb-run")
    };
    let out = run(&script);
    let log = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "exit {}: {log}", out.status);
    assert!(log.contains("last frame 2"), "{log}");
    assert!(
        log.contains("s.mdsurf:4: "),
        "the select count is not printed: {log}"
    );
    let image = mdsurf::render::RgbaImage::read_png(&shot).unwrap_or_else(|e| panic!("{e}: {log}"));
    assert_eq!((image.width, image.height), (400, 300));
    assert!(image.distinct_colours() > 10, "uniform screenshot: {log}");

    // An error in the middle: one line naming the file and line, exit status not 0.
    std::fs::write(&script, "frame 1\nrep 9 hide\nframe 2\n").unwrap();
    let out = run(&script);
    let log = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{log}");
    assert!(log.contains("s.mdsurf:2: no representation 9"), "{log}");
}
