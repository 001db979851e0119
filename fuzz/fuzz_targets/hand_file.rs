//! A hand file on any text, read against the study's vehicle and audited when it reads: an
//! audit report or one error naming the file and line, never a stack overflow (a formula nested
//! 30,000 deep), a hang (lets that grow exponentially) or a panic.
#![no_main]
#![deny(warnings)]

mod common;

use common::vehicle8;
use libfuzzer_sys::fuzz_target;
use twv_analysis::hand_file::{audit_hand_model, read_hand_file, HandAuditSettings};

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
