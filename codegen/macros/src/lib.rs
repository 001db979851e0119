//! `twv_model!`: turn a model IR file into a Rust model at compile time.
//!
//! ```text
//! twv_macros::twv_model!(ir = "ir/vehicle8.json", name = Vehicle8);
//! twv_macros::twv_model!(ir = "ir/vehicle8.json", name = Vehicle8, bake = "../vehicles/paper.toml");
//! twv_macros::twv_model!(ir = "ir/lorenz.json", name = Lorenz, bake = defaults);
//! ```
//!
//! - `ir`: the IR file; `name`: the struct to emit; `bake` (optional): fold the parameters as
//!   constants read from this TOML file, or from the IR defaults (`bake = defaults`). Without
//!   `bake` the struct holds its parameters at run time.
//! - Relative paths are relative to the `CARGO_MANIFEST_DIR` of the crate calling the macro,
//!   or, when the file is not there, to the nearest parent directory that has it (so paths from
//!   the workspace root work in every member crate), or else to this macro crate's directory
//!   and its parents; absolute paths are used as they are. The expansion refers to
//!   `::twv_model` (the traits) and `::twv_kernels` (sincos, ISA choice, lanes), so the calling
//!   crate depends on both.
//! - The expansion `include_bytes!`es every file it read, so editing the IR or the baked TOML
//!   rebuilds the calling crate with the new code.
//! - Any problem with a file becomes a `compile_error!` naming the file (as written in the call)
//!   and the problem.
//!
//! This crate is a thin shell: all the work is in `twv-ir` (reading, validating) and `twv-emit`.

use std::path::PathBuf;

use proc_macro::TokenStream;
use proc_macro2::{Span, TokenStream as TokenStream2};
use quote::quote;
use syn::parse::{Parse, ParseStream};
use syn::punctuated::Punctuated;
use syn::{parse_macro_input, Ident, LitStr, Token};

/// Emit a model from a twv IR file (see the crate documentation).
#[proc_macro]
pub fn twv_model(input: TokenStream) -> TokenStream {
    let args = parse_macro_input!(input as Args);
    match expand(&args) {
        Ok(tokens) => tokens.into(),
        Err(err) => err.to_compile_error().into(),
    }
}

/// The value of one `key = value` argument.
enum Value {
    Str(LitStr),
    Ident(Ident),
}

struct Args {
    ir: LitStr,
    name: Ident,
    bake: Option<Value>,
}

impl Parse for Args {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        let (mut ir, mut name, mut bake) = (None, None, None);
        let pairs = Punctuated::<(Ident, Value), Token![,]>::parse_terminated_with(input, pair)?;
        for (key, value) in pairs {
            match (key.to_string().as_str(), value) {
                ("ir", Value::Str(s)) if ir.is_none() => ir = Some(s),
                ("name", Value::Ident(i)) if name.is_none() => name = Some(i),
                ("bake", v) if bake.is_none() => bake = Some(v),
                _ => {
                    let msg = "expected `ir = \"file.json\"`, `name = Ident` and optionally `bake = \"file.toml\"` or `bake = defaults`, each once";
                    return Err(syn::Error::new(key.span(), msg));
                }
            }
        }
        let missing = |what: &str| syn::Error::new(Span::call_site(), format!("missing `{what}`"));
        Ok(Args {
            ir: ir.ok_or_else(|| missing("ir = \"file.json\""))?,
            name: name.ok_or_else(|| missing("name = Ident"))?,
            bake,
        })
    }
}

fn pair(input: ParseStream) -> syn::Result<(Ident, Value)> {
    let key: Ident = input.parse()?;
    input.parse::<Token![=]>()?;
    let value = if input.peek(LitStr) {
        Value::Str(input.parse()?)
    } else {
        Value::Ident(input.parse()?)
    };
    Ok((key, value))
}

/// Resolve a path argument: absolute paths as they are; a relative path against the calling
/// crate's `CARGO_MANIFEST_DIR`, or else against the nearest parent directory where it exists
/// (so a workspace-root path such as `generated/ir/vehicle8.json` works from every member, and
/// from the scratch crates of compile-fail tests under `target/`), or else against this macro
/// crate's own directory and its parents (the scratch crates are under a `CARGO_TARGET_DIR`
/// outside the workspace when a developer sets one).
fn resolve(lit: &LitStr) -> syn::Result<PathBuf> {
    let path = PathBuf::from(lit.value());
    if path.is_absolute() {
        return Ok(path);
    }
    let dir = std::env::var_os("CARGO_MANIFEST_DIR").ok_or_else(|| {
        syn::Error::new(
            lit.span(),
            "CARGO_MANIFEST_DIR is not set (not built by cargo?)",
        )
    })?;
    let dir = PathBuf::from(dir);
    let own = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    (dir.ancestors().chain(own.ancestors()))
        .map(|base| base.join(&path))
        .find(|candidate| candidate.is_file())
        .ok_or_else(|| {
            let msg = format!(
                "{}: no such file in the calling crate's directory, twv-macros' own \
                 directory, or any of their parents",
                lit.value()
            );
            syn::Error::new(lit.span(), msg)
        })
}

/// `include_bytes!` of a file, so cargo rebuilds the caller when it changes.
fn track(path: &std::path::Path) -> TokenStream2 {
    let path = path.display().to_string();
    quote!(
        const _: &[u8] = include_bytes!(#path);
    )
}

fn read(lit: &LitStr) -> syn::Result<(String, TokenStream2)> {
    let path = resolve(lit)?;
    let text = std::fs::read_to_string(&path)
        .map_err(|e| syn::Error::new(lit.span(), format!("{}: cannot read: {e}", lit.value())))?;
    Ok((text, track(&path)))
}

fn expand(args: &Args) -> syn::Result<TokenStream2> {
    let (text, track_ir) = read(&args.ir)?;
    let ir = twv_ir::parse_ir(&text, &args.ir.value())
        .map_err(|e| syn::Error::new(args.ir.span(), e.to_string()))?;
    let (params, track_bake) = match &args.bake {
        None => (twv_emit::Params::Runtime, TokenStream2::new()),
        Some(Value::Ident(i)) if i == "defaults" => {
            let source = format!("the defaults of {}", args.ir.value());
            (
                twv_emit::Params::Baked {
                    values: ir.defaults(),
                    source,
                },
                TokenStream2::new(),
            )
        }
        Some(Value::Ident(i)) => {
            return Err(syn::Error::new(
                i.span(),
                "`bake` takes a TOML file name or `defaults`",
            ));
        }
        Some(Value::Str(lit)) => {
            let (text, track) = read(lit)?;
            let values = twv_ir::parse_params(&text, &lit.value(), ir.params())
                .map_err(|e| syn::Error::new(lit.span(), e.to_string()))?;
            (
                twv_emit::Params::Baked {
                    values,
                    source: lit.value(),
                },
                track,
            )
        }
    };
    let options = twv_emit::Options {
        name: args.name.to_string(),
        params,
    };
    let model = twv_emit::emit_model(&ir, &options)
        .map_err(|e| syn::Error::new(args.name.span(), e.to_string()))?;
    Ok(quote! {
        #track_ir
        #track_bake
        #model
    })
}
