//! A hand file on any text, read against the study's vehicle and audited when it reads: an
//! audit report or one error naming the file and line, never a stack overflow (a formula nested
//! 30,000 deep), a hang (lets that grow exponentially) or a panic.
#![no_main]
#![deny(warnings)]

use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use twv_analysis::hand_file::{audit_hand_model, read_hand_file, HandAuditSettings};
use twv_analysis::model::{ModelSpec, ResolvedModel};

fn vehicle8() -> &'static ResolvedModel {
    static MODEL: OnceLock<ResolvedModel> = OnceLock::new();
    MODEL.get_or_init(|| ModelSpec::shipped("vehicle8").resolve().expect("vehicle8"))
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let model = vehicle8();
    let Ok(hand) = read_hand_file(text, "fuzz.toml", &model.ir) else {
        return;
    };
    // Few samples: the fuzzer wants many files a second, not a thorough audit of one.
    let settings = HandAuditSettings {
        samples: 2,
        ..HandAuditSettings::default()
    };
    if let Ok(report) = audit_hand_model(&model.ir, &model.params, &hand, &settings) {
        let _ = report.table();
    }
});
