//! The time the viewer shows belongs to the frame on screen (issue 30 section 4): after seeking
//! to and stepping through frames of YiiP (times 0 to 80,000 ps), the shown frame's time is that
//! frame's time in the trajectory, and the label the timeline draws says so. (While a frame is
//! still computing, the label names the frame on screen: `timeline::time_label`'s unit test.)

use std::sync::Arc;
use std::time::Duration;

use mdsurf::app::source::{FrameSource, open_files};
use mdsurf::app::state::{AppCore, Command};
use mdsurf::app::timeline::{TimelineCmd, time_label};
use mdsurf::app::worker::Worker;
use mdsurf::surface::CpuEngine;

use crate::data_support::data;

#[test]
fn shown_time_is_the_shown_frames_time() {
    let source: Arc<dyn FrameSource> =
        open_files(&data("YiiP_lipids.gro.gz"), Some(&data("YiiP_lipids.xtc"))).expect("open YiiP");
    let times: Vec<Option<f64>> = (0..source.len())
        .map(|i| source.read_frame(i).expect("frame").time_ps)
        .collect();
    assert!(times.iter().all(Option::is_some), "{times:?}");
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
    let worker = Worker::spawn(Box::new(CpuEngine::new()), Box::new(|| {}));
    let mut core = AppCore::new(worker);
    core.base.spacing = 3.0;
    core.set_source(source.clone());
    let check = |core: &mut AppCore, what: &str| {
        assert!(
            core.wait_idle(Duration::from_secs(300)),
            "{what}: timed out"
        );
        assert!(core.error.is_none(), "{what}: {:?}", core.error);
        let shown = core.shown.as_ref().expect("a frame on screen");
        let frame = shown.computed.frame;
        assert_eq!(frame, core.timeline.current, "{what}: frame on screen");
        assert_eq!(
            shown.computed.time_ps, times[frame],
            "{what}: time of frame {frame}"
        );
        let label = time_label(core.timeline.current, Some((frame, shown.computed.time_ps)));
        assert_eq!(
            label,
            format!("t = {:.1} ps", times[frame].unwrap()),
            "{what}"
        );
    };
    check(&mut core, "first frame");
    for f in [4, 0, 3, 1, 4] {
        core.apply(Command::Timeline(TimelineCmd::Seek(f)));
        core.request_current();
        check(&mut core, &format!("seek {f}"));
    }
    for step in [1, 1, -1, 1] {
        core.apply(Command::Timeline(TimelineCmd::Step(step)));
        core.request_current();
        check(&mut core, &format!("step {step}"));
    }
}
