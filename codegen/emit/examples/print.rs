//! Print the emitted code of an IR file: `cargo run -p twv-emit --example print -- FILE [TOML]`.
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(file) = args.first() else {
        eprintln!("usage: print FILE.json [PARAMS.toml]");
        std::process::exit(2);
    };
    let run = || -> Result<String, Box<dyn std::error::Error>> {
        let ir = twv_ir::load_ir(file)?;
        let params = match args.get(1) {
            Some(toml) => twv_emit::Params::Baked {
                values: ir.load_params(toml)?,
                source: toml.clone(),
            },
            None => twv_emit::Params::Runtime,
        };
        Ok(twv_emit::format_model(
            &ir,
            &twv_emit::Options {
                name: "Model".into(),
                params,
            },
        )?)
    };
    match run() {
        Ok(source) => print!("{source}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
