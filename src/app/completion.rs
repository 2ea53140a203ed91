//! When each frame's GPU work was done, as the CPU sees it: a thread that waits on each
//! frame's last submission (wgpu's blocking poll) and notes the instant it returned. A
//! late frame is then judged by when it was done, not by an estimate from its GPU time
//! (timestamps leave out the queueing before a frame and, on a CPU adapter, misplace work).

use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The longest the thread waits for one submission: a device that hangs longer has failed
/// in a way the frame loop reports itself.
const WAIT_AT_MOST: Duration = Duration::from_secs(10);

/// The watching thread and its two channels.
pub(crate) struct CompletionWatcher {
    submissions: Option<mpsc::Sender<(u64, wgpu::SubmissionIndex)>>,
    done: mpsc::Receiver<(u64, Instant)>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl CompletionWatcher {
    /// Starts the thread over `device`.
    pub(crate) fn new(device: wgpu::Device) -> CompletionWatcher {
        let (submissions, waiting) = mpsc::channel::<(u64, wgpu::SubmissionIndex)>();
        let (finished, done) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("vrao frame completion".into())
            .spawn(move || {
                while let Ok((frame, index)) = waiting.recv() {
                    let wait = wgpu::PollType::Wait { submission_index: Some(index), timeout: Some(WAIT_AT_MOST) };
                    if device.poll(wait).is_ok() && finished.send((frame, Instant::now())).is_err() {
                        break;
                    }
                }
            })
            .ok();
        CompletionWatcher { submissions: thread.is_some().then_some(submissions), done, thread }
    }

    /// Watches frame `frame`, whose last work is `index`.
    pub(crate) fn watch(&self, frame: u64, index: wgpu::SubmissionIndex) {
        if let Some(submissions) = &self.submissions {
            let _ = submissions.send((frame, index));
        }
    }

    /// The frames done since the last call, with the instant each was seen done.
    pub(crate) fn done(&self) -> Vec<(u64, Instant)> {
        self.done.try_iter().collect()
    }
}

impl Drop for CompletionWatcher {
    fn drop(&mut self) {
        // Closing the channel ends the thread after the wait it is in.
        self.submissions = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each watched submission comes back once, in order, seen no earlier than it was
    /// submitted; dropping the watcher ends its thread.
    #[test]
    fn each_watched_frame_comes_back_done_after_its_submission() {
        let gpu = vrao_render::open(vrao_render::BackendChoice::Auto).expect("a Vulkan device (lavapipe in CI)");
        let watcher = CompletionWatcher::new(gpu.device.clone());
        let mut submitted = Vec::new();
        for frame in 0..3u64 {
            let encoder = gpu.device.create_command_encoder(&Default::default());
            submitted.push(Instant::now());
            watcher.watch(frame, gpu.queue.submit([encoder.finish()]));
        }
        let mut done = Vec::new();
        let start = Instant::now();
        while done.len() < 3 && start.elapsed() < WAIT_AT_MOST {
            done.extend(watcher.done());
            std::thread::sleep(Duration::from_millis(1));
        }
        let frames: Vec<u64> = done.iter().map(|&(frame, _)| frame).collect();
        assert_eq!(frames, [0, 1, 2]);
        for (&(frame, at), &sent) in done.iter().zip(&submitted) {
            assert!(at >= sent, "frame {frame} seen done before it was submitted");
        }
        drop(watcher);
    }
}
