//! `mdsurf render --script FILE` (issue 30): a console session replayed headless. The script's
//! `screenshot` lines write their pictures, `view save` writes the state it built (the
//! representations added and edited, the frame, the look), and `-o` then draws the scene the
//! script left, at the frame it left: the same picture as `render --state` of the saved view at
//! that frame. A bad line stops the
//! run with one line naming the script and the line, and no `-o` file is written.

use mdsurf::render::RgbaImage;
use mdsurf::scene::representation::RepStyle;
use mdsurf::scene::state_file::StateFile;

use crate::cli_common::{data, have_gpu, mdsurf};

const SCRIPT: &str = "\
# a session typed in the console
rep add \"protein\" surface as prot
rep prot color chain
rep 1 hide
frame 3
fit \"protein\"
select \"resname ARG\"
screenshot first.png 160x120
rep prot opacity 0.5
view save view.toml
screenshot last.png 160x120
";

#[test]
fn a_script_builds_the_scene_its_pictures_and_the_output_show() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.txt"), SCRIPT).unwrap();
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let files = [top.as_str(), traj.as_str()];
    let common = ["--backend", "cpu", "--size", "160x120"];
    // No --frame: -o shows the frame the script left (its `frame 3`).
    let run = mdsurf(
        dir.path(),
        &[
            &["render"],
            &files[..],
            &["--script", "s.txt", "-o", "final.png"],
            &common[..],
        ]
        .concat(),
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    // The console's lines: the new representation, the fit, the count, the files written.
    for said in [
        "added representation 2 'prot'",
        "atoms (frame 3)",
        "wrote first.png",
    ] {
        assert!(
            run.stderr.contains(said),
            "{said:?} missing:\n{}",
            run.stderr
        );
    }
    // The saved view holds what the script did.
    let state = StateFile::load(&dir.path().join("view.toml")).expect("saved view");
    assert_eq!(state.trajectory.frame, 3);
    let reps = &state.representations;
    assert_eq!(reps.len(), 2, "{reps:?}");
    assert!(!reps[0].visible);
    assert_eq!(reps[1].name, "prot");
    assert_eq!(reps[1].style, RepStyle::Surface);
    assert_eq!(reps[1].opacity, 0.5);
    // The pictures: drawn, and the opacity change shows.
    let read = |name: &str| RgbaImage::read_png(&dir.path().join(name)).expect(name);
    let (first, last, output) = (read("first.png"), read("last.png"), read("final.png"));
    assert_eq!((first.width, first.height), (160, 120));
    assert!(first.distinct_colours() > 50, "a blank picture");
    assert!(!first.close_to(&last), "opacity 0.5 changed nothing");
    // -o shows the scene the script left: as `render --state` of the saved view does.
    let again = mdsurf(
        dir.path(),
        &[
            &["render"],
            &files[..],
            &["--state", "view.toml", "-o", "again.png", "--frame", "3"],
            &common[..],
        ]
        .concat(),
    );
    assert_eq!(again.code, 0, "{}", again.stderr);
    assert!(
        output.close_to(&read("again.png")),
        "--script and --state differ"
    );
    // ... and not frame 0, which --state alone starts from.
    let start = mdsurf(
        dir.path(),
        &[
            &["render"],
            &files[..],
            &["--state", "view.toml", "-o", "start.png"],
            &common[..],
        ]
        .concat(),
    );
    assert_eq!(start.code, 0, "{}", start.stderr);
    assert!(
        !output.close_to(&read("start.png")),
        "-o after a script drew frame 0, not the script's frame 3"
    );
    assert!(
        output.close_to(&last),
        "-o and the script's last screenshot differ"
    );
}

#[test]
fn a_bad_line_names_the_script_and_line_and_writes_no_output() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.txt"), "frame 1\nrep 9 hide\nframe 2\n").unwrap();
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let run = mdsurf(
        dir.path(),
        &[
            "render",
            &top,
            &traj,
            "--script",
            "s.txt",
            "-o",
            "out.png",
            "--backend",
            "cpu",
        ],
    );
    assert_eq!(run.code, 2, "{}", run.stderr);
    let lines: Vec<&str> = run
        .stderr
        .lines()
        .filter(|l| !l.trim().is_empty())
        .collect();
    assert_eq!(lines.len(), 1, "{}", run.stderr);
    assert!(
        lines[0].contains("s.txt:2:") && lines[0].contains("no representation 9"),
        "{}",
        lines[0]
    );
    assert!(!dir.path().join("out.png").exists());
}

/// Without a state file, a script starts from the representations the flags choose, as a
/// render without a script shows them: `--select`, `--opacity` and `--atoms` hold.
#[test]
fn a_script_starts_from_the_representations_of_the_flags() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.txt"), "frame 2\n").unwrap();
    let (top, traj) = (data("adk_open.pdb"), data("adk_dims.dcd"));
    let files = [top.as_str(), traj.as_str()];
    let common = ["--backend", "cpu", "--size", "160x120"];
    let flags = [
        "--select",
        "protein and resid 1:80",
        "--opacity",
        "0.4",
        "--atoms",
        "sticks",
    ];
    let render = |extra: &[&str], out: &str| {
        let run = mdsurf(
            dir.path(),
            &[&["render"], &files[..], extra, &["-o", out], &common[..]].concat(),
        );
        assert_eq!(run.code, 0, "{}", run.stderr);
        RgbaImage::read_png(&dir.path().join(out)).expect(out)
    };
    let scripted = render(
        &[&flags[..], &["--script", "s.txt"]].concat(),
        "scripted.png",
    );
    let plain = render(&[&flags[..], &["--frame", "2"]].concat(), "plain.png");
    assert!(
        scripted.close_to(&plain),
        "the script lost the flags' representations"
    );
    let defaults = render(&["--script", "s.txt"], "defaults.png");
    assert!(
        !scripted.close_to(&defaults),
        "--select, --opacity and --atoms changed nothing"
    );
}
