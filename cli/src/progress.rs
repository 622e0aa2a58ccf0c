//! Progress bars (indicatif) for the library's long jobs: the command's
//! [`mmbm::diagnostics::Progress`].

use indicatif::{ProgressBar, ProgressStyle};
use mmbm::diagnostics::{Progress, ProgressTask};

struct Bars;

struct Bar(ProgressBar);

impl Progress for Bars {
    fn start(&self, what: &str, total: u64) -> Box<dyn ProgressTask> {
        let bar = ProgressBar::new(total);
        let template = format!(
            "{what} {{pos}}/{{len}} [{{elapsed_precise}} < {{eta_precise}}] {{per_sec}} {{msg}}"
        );
        bar.set_style(
            ProgressStyle::with_template(&template)
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Box::new(Bar(bar))
    }
}

impl ProgressTask for Bar {
    fn message(&self, msg: &str) {
        self.0.set_message(msg.to_string());
    }
    fn advance(&self, n: u64) {
        self.0.inc(n);
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

/// Makes progress bars where the library's jobs report progress.
pub fn install() {
    mmbm::diagnostics::set_progress(Box::new(Bars));
}
