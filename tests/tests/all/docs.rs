//! The docs' option tables (`docs/src/jobs/options/<job>.md`) are made from the job registry and
//! must match it: a new option is documented by regenerating them
//! (`TWV_UPDATE_DOCS=1 cargo test -p twv-tests docs::`), never by hand.

use twv_analysis::jobs::options::display;
use twv_analysis::jobs::{registry, AnyJob, Kind};

use crate::common::repo;

/// The option table of one job, as the docs include it.
fn table(job: &dyn AnyJob) -> String {
    let mut md = format!(
        "<!-- generated from the job registry: TWV_UPDATE_DOCS=1 cargo test -p twv-tests docs:: -->\n\n\
         ## Options\n\n\
         The flags of `twv {command}`, the keywords of `twv.{name}(model, …)` and the `options` of \
         `POST /api/{name}`; the defaults are the library's. Besides them: the model flags \
         (`--model`, `--ir`, `--params`, `--runtime`) and `--out`, `--json`, `--settings`, \
         `--print-settings` ([Jobs](../jobs.md)).\n\n\
         | flag (Python keyword) | unit | default | what it does |\n|---|---|---|---|\n",
        name = job.name(),
        command = job.name().replace('_', "-")
    );
    for o in job.options() {
        let aliases: Vec<String> = o
            .aliases
            .iter()
            .map(|a| format!("`--{}`", a.replace('_', "-")))
            .collect();
        let flag = format!(
            "`--{}`{} ({}{})",
            o.name.replace('_', "-"),
            if aliases.is_empty() {
                String::new()
            } else {
                format!(", {}", aliases.join(", "))
            },
            o.name,
            if o.many { ", repeatable" } else { "" }
        );
        let default = match (&o.default, o.required, o.kind) {
            (_, true, _) => "required".to_string(),
            (_, _, Kind::Flag) => "off".to_string(),
            (v, _, _) => format!("`{}`", display(v)),
        };
        let choices = if o.choices.is_empty() {
            String::new()
        } else {
            format!(" One of: {}.", o.choices.join(", "))
        };
        md += &format!(
            "| {flag} | {} | {default} | {}.{choices} |\n",
            o.unit,
            // A table cell is Markdown with inline HTML: `|` ends the cell, `<model>` would be a
            // tag.
            o.help
                .replace('|', "\\|")
                .replace('<', "&lt;")
                .replace('>', "&gt;")
        );
    }
    md
}

#[test]
fn the_docs_option_tables_are_the_registrys() {
    let update = std::env::var_os("TWV_UPDATE_DOCS").is_some();
    let mut stale = Vec::new();
    for job in registry() {
        let path = repo(&format!("docs/src/jobs/options/{}.md", job.name()));
        let want = table(*job);
        if update {
            std::fs::write(&path, &want).unwrap();
        } else if std::fs::read_to_string(&path).ok().as_deref() != Some(want.as_str()) {
            stale.push(path.display().to_string());
        }
    }
    assert!(
        stale.is_empty(),
        "stale option tables (regenerate with TWV_UPDATE_DOCS=1 cargo test -p twv-tests docs::): {stale:?}"
    );
}
