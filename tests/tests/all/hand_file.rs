//! A user's hand file: formulas read with their precedence and errors at their column, and the
//! canonical form that prints a disagreement as the missing term.

mod parse {
    use twv_analysis::hand_file::expr::{Args, Expr, Var};
    use twv_analysis::hand_file::parse::*;

    fn scope() -> Scope {
        let mut s = Scope::new();
        s.insert("phi".into(), Expr::Var(Var::X(0)));
        s.insert("b".into(), Expr::Var(Var::P(0)));
        s
    }

    fn value(text: &str) -> f64 {
        let e = parse(text, &scope()).unwrap();
        e.eval(&Args {
            x: &[0.5],
            u: &[],
            p: &[2.0],
        })
    }

    #[test]
    fn precedence_and_associativity() {
        assert_eq!(value("1 + 2*3"), 7.0);
        assert_eq!(value("-b^2"), -4.0);
        assert_eq!(value("2^3^2"), 512.0);
        assert_eq!(value("b**3 / 4"), 2.0);
        assert_eq!(value("(1 + 2) * 3 - 4/2"), 7.0);
        assert_eq!(value("1.5e1 - 5"), 10.0);
        assert_eq!(value("b*sin(phi)^2"), 2.0 * 0.5f64.sin().powi(2));
        assert_eq!(value("b^-1"), 0.5);
    }

    #[test]
    fn errors_point_at_the_column() {
        let err = |t: &str| parse(t, &scope()).unwrap_err();
        assert_eq!(err("b * q").offset, 4);
        assert!(err("b * q").message.contains("`q`"));
        assert_eq!(err("sinh(phi)").offset, 0);
        assert_eq!(err("(b + 1").message, "expected `)`");
        assert_eq!(err("b +").offset, 3);
        assert!(err("b $ 2").message.contains('$'));
        assert!(err("b b").message.contains("after the formula"));
    }
}

mod normal {
    use twv_analysis::hand_file::expr::{Expr, Var};
    use twv_analysis::hand_file::normal::*;
    use twv_analysis::hand_file::parse::{parse, Scope};

    fn form(text: &str) -> String {
        let states = vec!["phi".to_string(), "w".to_string()];
        let params = vec!["m".to_string(), "b".to_string()];
        let names = Names {
            states: &states,
            inputs: &[],
            params: &params,
        };
        let mut scope = Scope::new();
        scope.insert("phi".into(), Expr::Var(Var::X(0)));
        scope.insert("w".into(), Expr::Var(Var::X(1)));
        scope.insert("m".into(), Expr::Var(Var::P(0)));
        scope.insert("b".into(), Expr::Var(Var::P(1)));
        normal_form(&parse(text, &scope).unwrap(), &names)
            .unwrap()
            .print(&names)
    }

    #[test]
    fn equal_expressions_have_equal_forms() {
        assert_eq!(form("m*b*(w + 1)"), form("b*w*m + m*b"));
        assert_eq!(form("sin(phi)^2 + cos(phi)^2"), "1");
        assert_eq!(form("sin(2*phi)"), form("2*sin(phi)*cos(phi)"));
        assert_eq!(form("cos(2*phi)"), form("1 - 2*sin(phi)^2"));
        assert_eq!(form("tan(phi)*cos(phi)"), form("sin(phi)"));
        assert_eq!(form("(m + b)/m"), form("1 + b/m"));
        assert_eq!(form("(m*w)^2/(m + b)"), form("m^2*w^2/(b + m)"));
    }

    #[test]
    fn differences_print_the_missing_term() {
        assert_eq!(form("m*b*sin(phi)*w^2 - 2*m"), "-2*m + m*b*sin(phi)*w^2");
        assert_eq!(form("-b/m"), "-b/m");
        assert_eq!(form("0.5*m*w^2"), "0.5*m*w^2");
        assert_eq!(form("sqrt(m)*2"), "2*sqrt(m)");
    }

    #[test]
    fn expansions_are_bounded() {
        let states: Vec<String> = ["a", "b", "c", "d"].map(String::from).to_vec();
        let names = Names {
            states: &states,
            inputs: &[],
            params: &[],
        };
        let sum = (1..4).fold(Expr::Var(Var::X(0)), |acc, i| {
            Expr::sum(acc, Expr::Var(Var::X(i)))
        });
        let power = |n: f64| Expr::Pow(Box::new(sum.clone()), Box::new(Expr::Num(n)));
        // (a + b + c + d)^10 has C(13, 3) = 286 terms; ^30 would have 5456.
        assert_eq!(normal_form(&power(10.0), &names).unwrap().len(), 286);
        assert_eq!(normal_form(&power(30.0), &names), Err(TooLarge));
    }
}

/// The hand files of examples/hand/ against the derivation, and the same files with one planted
/// error each: the audit names the entry and prints the planted term as hand − derived.
mod audit {
    use std::path::PathBuf;

    use twv_analysis::api::{audit_hand, HandSource};
    use twv_analysis::hand_file::{HandAuditReport, HandAuditSettings};
    use twv_analysis::model::{ModelSource, ModelSpec, ParamSource, ResolvedModel};

    fn repo(path: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(path)
    }

    fn hand_text(model: &str) -> String {
        std::fs::read_to_string(repo(&format!("examples/hand/{model}.toml"))).unwrap()
    }

    fn resolved(model: &str) -> ResolvedModel {
        let params = match model {
            "segway7" => ParamSource::File(repo("vehicles/segway.toml")),
            "lorenz" | "whipple" => ParamSource::Defaults,
            _ => ParamSource::File(repo("vehicles/paper.toml")),
        };
        ModelSpec {
            model: ModelSource::Shipped(model.into()),
            params,
            ..ModelSpec::default()
        }
        .resolve()
        .unwrap()
    }

    fn audit_text(model: &ResolvedModel, text: &str) -> HandAuditReport {
        let source = HandSource::Text {
            text: text.to_string(),
            origin: "planted.toml".into(),
        };
        audit_hand(model, &source, &HandAuditSettings::default()).unwrap()
    }

    /// `text` with `from` replaced by `to` exactly once (so that a test cannot silently plant
    /// nothing).
    fn plant(text: &str, from: &str, to: &str) -> String {
        assert_eq!(text.matches(from).count(), 1, "`{from}` occurs once");
        text.replacen(from, to, 1)
    }

    #[test]
    fn the_example_hand_files_agree_with_the_derivation() {
        for name in ["vehicle8", "vehicle7", "segway7", "lorenz"] {
            let model = resolved(name);
            let report = audit_text(&model, &hand_text(name));
            assert!(report.passed, "{}", report.table());
            assert_eq!(report.samples, 202);
            let expected = if name == "lorenz" { 2 } else { 6 };
            assert_eq!(report.quantities.len(), expected, "{name}");
            for q in &report.quantities {
                assert!(q.max_rel < 1e-13, "{name} {}: {:e}", q.quantity, q.max_rel);
            }
        }
    }

    #[test]
    fn the_readme_example_agrees_with_the_derivation() {
        let readme = std::fs::read_to_string(repo("docs/src/hand-file.md")).unwrap();
        let start = readme
            .find("# examples/hand/vehicle7.toml (abridged)")
            .expect("the hand-file page's example");
        let block = &readme[start..start + readme[start..].find("```").unwrap()];
        let report = audit_text(&resolved("vehicle7"), block);
        assert!(report.passed, "{}", report.table());
    }

    #[test]
    fn another_parameter_file_and_the_ir_file_agree_too() {
        // The paper's vehicle7 file with the Segway's parameters: the formulas are the same.
        let model = ModelSpec {
            model: ModelSource::IrFile(repo("generated/ir/vehicle7.json")),
            params: ParamSource::File(repo("vehicles/segway.toml")),
            ..ModelSpec::default()
        }
        .resolve()
        .unwrap();
        let report = audit_text(&model, &hand_text("vehicle7"));
        assert!(report.passed, "{}", report.table());
    }

    /// (model, from, to, the first entry, hand − derived).
    const PLANTED: [(&str, &str, &str, &str, &str); 10] = [
        // A dropped gyroscopic term (in the Coriolis-matrix form: C[v_x, w_z] p_w_z).
        (
            "vehicle8",
            "\"-m2*b*sp*w_z\"]",
            "\"0\"]",
            "Cp[v_x]",
            "m2*b*sin(phi)*w_z^2",
        ),
        // A flipped gravity sign.
        (
            "vehicle8",
            "\"-m2*g*b*sp\"",
            "\"m2*g*b*sp\"",
            "F[w_y]",
            "2*m2*g*b*sin(phi)",
        ),
        // A wrong inertia in one entry.
        (
            "vehicle8",
            "Ip = \"I2_yy",
            "Ip = \"I2_xx",
            "M[w_y,w_y]",
            "I2_xx - I2_yy",
        ),
        (
            "vehicle7",
            "(w_y^2 + w_z^2)",
            "w_y^2",
            "Cp[v_x]",
            "m2*b*sin(phi)*w_z^2",
        ),
        (
            "vehicle7",
            "\"-m2*g*b*sin(phi)\"",
            "\"m2*g*b*sin(phi)\"",
            "F[w_y]",
            "2*m2*g*b*sin(phi)",
        ),
        (
            "vehicle7",
            "\"I1_zz + I2_zz",
            "\"I1_yy + I2_zz",
            "M[w_z,w_z]",
            "I1_yy - I1_zz",
        ),
        (
            "segway7",
            " + m2*b*sin(phi)*v_x*w_z\"",
            "\"",
            "Cp[w_z]",
            "-m2*b*sin(phi)*v_x*w_z",
        ),
        (
            "segway7",
            "\"-m2*g*b*sin(phi)\"",
            "\"m2*g*b*sin(phi)\"",
            "F[w_y]",
            "2*m2*g*b*sin(phi)",
        ),
        (
            "segway7",
            "2*J_d + rolling",
            "J_d + rolling",
            "M[w_z,w_z]",
            "-J_d",
        ),
        ("lorenz", "x*(rho - z)", "x*(rho + z)", "f[y]", "2*x*z"),
    ];

    #[test]
    fn a_planted_error_is_named_and_printed_as_the_term() {
        for (name, from, to, entry, difference) in PLANTED {
            let model = resolved(name);
            let report = audit_text(&model, &plant(&hand_text(name), from, to));
            assert!(!report.passed, "{name}: {from} -> {to}");
            let first = &report.disagreements[0];
            assert_eq!(first.label, entry, "{name}: {}", report.table());
            assert!(first.line > 0, "{name}: the entry's line");
            assert!(first.max_rel > 1e-3, "{name}: {:e}", first.max_rel);
            assert_eq!(first.difference.as_deref(), Some(difference), "{name}");
            // Only the planted entry and what follows from it (f, ∂f/∂x) disagree.
            for d in &report.disagreements[1..] {
                let quantity = d.label.split('[').next().unwrap();
                assert!(
                    d.label == entry || quantity == "f" || quantity == "jac_x",
                    "{name}: {} disagrees too",
                    d.label
                );
            }
            let worst = report.worst.as_deref().unwrap();
            assert!(report.disagreements.iter().any(|d| d.label == worst));
            let table = report.table();
            assert!(
                table.contains(&format!("{entry} = {difference}")),
                "{table}"
            );
            assert!(
                table.contains("first: ") && table.contains("worst: "),
                "{table}"
            );
        }
    }

    #[test]
    fn a_term_that_vanishes_for_this_vehicle_shows_with_the_parameters_varied() {
        // vehicles/paper.toml has I2_xx = I2_yy: the swapped inertia agrees at its values.
        let model = resolved("vehicle8");
        let text = plant(&hand_text("vehicle8"), "Ip = \"I2_yy", "Ip = \"I2_xx");
        let audit = |param_spread| {
            let settings = HandAuditSettings {
                param_spread,
                ..HandAuditSettings::default()
            };
            let source = HandSource::Text {
                text: text.clone(),
                origin: "swapped.toml".into(),
            };
            audit_hand(&model, &source, &settings).unwrap()
        };
        assert!(audit(1.0).passed, "at the given values only it agrees");
        let varied = audit(2.0);
        assert!(!varied.passed);
        let first = &varied.disagreements[0];
        assert_eq!(first.label, "M[w_y,w_y]");
        assert_eq!(first.difference.as_deref(), Some("I2_xx - I2_yy"));
        assert!(first.max_rel_at_given_params <= 1e-15, "{first:?}");
        assert!(
            !first.params.is_empty(),
            "the varied parameters are reported"
        );
        assert!(varied
            .table()
            .contains("it holds for these values, not as a formula"));
    }

    #[test]
    fn equivalent_forms_of_a_wrong_entry_give_the_same_difference() {
        // The same wrong entry written three ways prints one canonical difference.
        let model = resolved("vehicle7");
        let base = hand_text("vehicle7");
        let wrong = "-m2*b*sin(phi)*(w_y^2 + w_z^2)";
        for form in [
            "-m2*b*sin(phi)*(w_y^2 + w_z^2) + b*m1*cos(phi)",
            "-(m2*sin(phi)*w_y^2 + m2*sin(phi)*w_z^2 - m1*cos(phi))*b",
            "-m2*b*sin(phi)*(w_y^2 + w_z^2) + b*m1*cos(phi)*(sin(theta)^2 + cos(theta)^2)",
        ] {
            let report = audit_text(&model, &plant(&base, wrong, form));
            let first = &report.disagreements[0];
            assert_eq!(first.label, "Cp[v_x]");
            assert_eq!(first.difference.as_deref(), Some("m1*b*cos(phi)"), "{form}");
        }
    }

    /// (from, to, the first disagreeing entry) planted into the bicycle's linear form.
    const PLANTED_LINEAR: [(&str, &str, &str); 3] = [
        // A dropped gyrostatic term of the front wheel.
        ("S_F*cos(lambda) + I_Txz", "I_Txz", "C1[phi,delta]"),
        // A flipped gravity sign.
        (
            "[\"m_T*z_T\", \"-S_A\"]",
            "[\"-m_T*z_T\", \"-S_A\"]",
            "K0[phi,phi]",
        ),
        // A wrong inertia in a [let] name used by M and C1.
        (
            "I_Tzz = \"I_Rxx + I_Bzz",
            "I_Tzz = \"I_Rxx + I_Byy",
            "M[delta,delta]",
        ),
    ];

    #[test]
    fn the_bicycles_linearised_benchmark_equations_agree_with_the_derivation() {
        let model = resolved("whipple");
        let report = audit_text(&model, &hand_text("whipple"));
        assert!(report.passed, "{}", report.table());
        assert_eq!(report.form, "linear");
        let names: Vec<&str> = report.quantities.iter().map(|q| q.quantity).collect();
        assert_eq!(names, ["M", "C1", "K0", "K2", "A"]);
        for q in &report.quantities {
            assert!(q.max_rel < 1e-13, "{}: {:e}", q.quantity, q.max_rel);
        }
        for (from, to, entry) in PLANTED_LINEAR {
            let report = audit_text(&model, &plant(&hand_text("whipple"), from, to));
            assert!(!report.passed, "{from} -> {to}");
            let first = &report.disagreements[0];
            assert_eq!(first.label, entry, "{}", report.table());
            assert!(first.line > 0 && first.max_rel > 1e-3, "{first:?}");
            // The derived matrices hold M⁻¹: no symbolic difference, but the state matrices at
            // some speed disagree too, and name it.
            assert!(first.difference.is_none());
            let a = report
                .disagreements
                .iter()
                .find(|d| d.label.starts_with("A["))
                .expect("the state matrix disagrees too");
            assert_eq!(a.x[0].0, "v");
        }
    }

    #[test]
    fn a_linear_form_needs_a_steady_motion_and_parameters_only() {
        let err = |model: &str, text: &str| {
            let source = HandSource::Text {
                text: text.to_string(),
                origin: "lin.toml".into(),
            };
            audit_hand(&resolved(model), &source, &HandAuditSettings::default())
                .unwrap_err()
                .to_string()
        };
        let matrix = "phi = [\"1\", \"0\"]\ndelta = [\"0\", \"1\"]\n";
        let text =
            |m: &str| format!("[linear.M]\n{m}[linear.C1]\n{m}[linear.K0]\n{m}[linear.K2]\n{m}");
        let e = err("vehicle8", &text(matrix));
        assert!(e.contains("describes no steady motion"), "{e}");
        let with_state = "phi = [\"phi\", \"0\"]\ndelta = [\"0\", \"1\"]\n";
        let e = err("whipple", &text(with_state));
        assert!(
            e.contains("lin.toml:2") && e.contains("unknown name `phi`"),
            "{e}"
        );
        let e = err(
            "whipple",
            "[linear.M]\nphi = [\"1\"]\ndelta = [\"0\", \"1\"]\n",
        );
        assert!(e.contains("M[phi] has 1 entries"), "{e}");
        let e = err("whipple", &(text(matrix) + "[f]\nphi = 0\n"));
        assert!(e.contains("give one form"), "{e}");
    }
}

/// A hand file is untrusted input: what a formula can cost is bounded as it is read, and the
/// comparison cannot fail a correct formula on round-off (issue 38).
mod hostile {
    use std::time::{Duration, Instant};

    use twv_analysis::api::{audit_hand, HandSource};
    use twv_analysis::hand_file::expr::{Args, Expr, Var};
    use twv_analysis::hand_file::normal::{normal_form, Names};
    use twv_analysis::hand_file::parse::{parse, Scope, MAX_DEPTH, MAX_NODES};
    use twv_analysis::hand_file::{read_hand_file, HandAuditSettings};
    use twv_analysis::model::{ModelSource, ModelSpec, ParamSource};

    fn scope() -> Scope {
        let mut s = Scope::new();
        s.insert("phi".into(), Expr::Var(Var::X(0)));
        s.insert("b".into(), Expr::Var(Var::P(0)));
        s.insert("pi".into(), Expr::Pi);
        s
    }

    fn value(e: &Expr, phi: f64) -> f64 {
        e.eval(&Args {
            x: &[phi],
            u: &[],
            p: &[2.0],
        })
    }

    #[test]
    fn deep_nesting_is_an_error_naming_the_limit_not_a_stack_overflow() {
        for text in [
            format!("{}phi{}", "(".repeat(30_000), ")".repeat(30_000)),
            format!("{}phi", "-".repeat(30_000)),
            format!("{}phi{}", "sin(".repeat(30_000), ")".repeat(30_000)),
            format!("phi{}", "^phi".repeat(30_000)),
            // A product's factors nest: the tree of a*b*c*… is as deep as it is long.
            format!("phi{}", "*phi".repeat(MAX_DEPTH + 1)),
        ] {
            let e = parse(&text, &scope()).unwrap_err();
            assert!(
                e.message
                    .contains(&format!("deeper than {MAX_DEPTH} levels")),
                "{}",
                e.message
            );
        }
        // Just inside the limit reads.
        let inside = format!("{}phi{}", "(".repeat(150), ")".repeat(150));
        assert_eq!(value(&parse(&inside, &scope()).unwrap(), 0.5), 0.5);
    }

    #[test]
    fn a_flat_sum_of_50000_terms_reads_and_evaluates_in_a_balanced_tree() {
        // 300 KB of formula, under the hand-file size cap: alternating signs, Σ = 25 000 phi - 25 000 b.
        let mut text = String::from("phi");
        for k in 1..50_000 {
            text.push_str(if k % 2 == 1 { " - b" } else { " + phi" });
        }
        let e = parse(&text, &scope()).unwrap();
        assert_eq!(value(&e, 0.5), 25_000.0 * 0.5 - 25_000.0 * 2.0);
        // Short sums keep their left-to-right order (bit for bit what they were).
        let short = parse("phi - b + phi - b", &scope()).unwrap();
        assert!(matches!(short, Expr::Sub(..)));
        let names = Names {
            states: &["phi".to_string()],
            inputs: &[],
            params: &["b".to_string()],
        };
        // The balanced tree has the same canonical form as the sum it is.
        let long = format!("phi{}", " - b + phi".repeat(20));
        let form = normal_form(&parse(&long, &scope()).unwrap(), &names).unwrap();
        assert_eq!(form.print(&names), "-20*b + 21*phi");
    }

    fn file(body: &str) -> String {
        format!("model = \"lorenz\"\n{body}")
    }

    fn read(text: &str) -> Result<(), String> {
        let model = ModelSpec {
            model: ModelSource::Shipped("lorenz".into()),
            params: ParamSource::Defaults,
            ..ModelSpec::default()
        }
        .resolve()
        .unwrap();
        read_hand_file(text, "hostile.toml", &model.ir)
            .map(|_| ())
            .map_err(|e| e.to_string())
    }

    #[test]
    fn lets_that_grow_exponentially_are_refused_before_they_are_copied() {
        // a1 = x + x, a2 = a1 + a1, …: a40 would have 2^41 nodes.
        let mut lets = String::from("[let]\na0 = \"x\"\n");
        for k in 1..=40 {
            lets.push_str(&format!("a{k} = \"a{} * a{}\"\n", k - 1, k - 1));
        }
        let text = file(&format!("{lets}[f]\nx = \"a40\"\ny = 0\nz = 0\n"));
        let started = Instant::now();
        let e = read(&text).unwrap_err();
        assert!(e.contains(&format!("more than {MAX_NODES}")), "{e}");
        assert!(e.contains("let a"), "{e}");
        assert!(started.elapsed() < Duration::from_secs(5));
    }

    #[test]
    fn a_let_cycle_is_named_as_a_cycle_and_a_long_chain_reads_once_each() {
        let text =
            file("[let]\na = \"b + 1\"\nb = \"c*2\"\nc = \"a\"\n[f]\nx = \"a\"\ny = 0\nz = 0\n");
        let e = read(&text).unwrap_err();
        assert!(e.contains("cycle: a → b → c → a"), "{e}");
        assert!(e.contains("hostile.toml:"), "{e}");
        let text = file("[let]\na = \"a\"\n[f]\nx = \"a\"\ny = 0\nz = 0\n");
        assert!(read(&text).unwrap_err().contains("cycle: a → a"));
        // 20 000 lets, each using the one after it (the worst order for a retrying reader).
        let mut lets = String::from("[let]\n");
        for k in 0..20_000 {
            lets.push_str(&format!("l{k} = \"l{}\"\n", k + 1));
        }
        lets.push_str("l20000 = \"x\"\n");
        let text = file(&format!("{lets}[f]\nx = \"nowhere\"\ny = 0\nz = 0\n"));
        let started = Instant::now();
        let e = read(&text).unwrap_err();
        assert!(e.contains("unknown name `nowhere`"), "{e}");
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "{:?}",
            started.elapsed()
        );
        assert!(read(&file("[f]\nx = \"1e999\"\ny = 0\nz = 0\n"))
            .unwrap_err()
            .contains("`1e999` is not a finite number"));
    }

    #[test]
    fn pi_is_exact_in_the_simplified_difference() {
        let names = Names {
            states: &["phi".to_string()],
            inputs: &[],
            params: &["b".to_string()],
        };
        let form = |t: &str| {
            normal_form(&parse(t, &scope()).unwrap(), &names)
                .unwrap()
                .print(&names)
        };
        assert_eq!(form("sin(pi - phi)"), "sin(phi)");
        assert_eq!(form("cos(phi - pi/2)"), "sin(phi)");
        assert_eq!(form("sin(phi + pi)"), "-sin(phi)");
        assert_eq!(form("cos(2*phi + 3*pi/2) - sin(2*phi)"), "0");
        assert_eq!(form("sin(pi - phi) - sin(phi)"), "0");
        // Elsewhere pi is its value, as the derivation writes it.
        assert_eq!(form("2*pi*b"), format!("{}*b", 2.0 * std::f64::consts::PI));
    }

    fn vehicle8() -> twv_analysis::model::ResolvedModel {
        let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
        ModelSpec {
            model: ModelSource::Shipped("vehicle8".into()),
            params: ParamSource::File(root.join("vehicles/paper.toml")),
            ..ModelSpec::default()
        }
        .resolve()
        .unwrap()
    }

    fn audit(text: &str) -> twv_analysis::hand_file::HandAuditReport {
        let source = HandSource::Text {
            text: text.to_string(),
            origin: "pi.toml".into(),
        };
        audit_hand(&vehicle8(), &source, &HandAuditSettings::default()).unwrap()
    }

    fn vehicle8_hand() -> String {
        let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
        std::fs::read_to_string(root.join("examples/hand/vehicle8.toml")).unwrap()
    }

    #[test]
    fn round_off_at_the_hanging_rest_state_does_not_fail_a_correct_formula() {
        // sin(pi - phi) is sin(phi), but at phi = pi (the hanging rest state, where the whole of
        // F is round-off) it evaluates to 1.2e-16 where the derivation has 0.
        let text = vehicle8_hand();
        for correct in ["sin(pi - phi)", "cos(phi - pi/2)", "-sin(phi + pi)"] {
            let planted = text.replacen("sp = \"sin(phi)\"", &format!("sp = \"{correct}\""), 1);
            assert_ne!(planted, text);
            let report = audit(&planted);
            assert!(report.passed, "{correct}: {}", report.table());
        }
        // A wrong one still fails, with its term.
        let wrong = text.replacen("-m2*g*b*sp", "-m2*g*b*sin(pi + phi)", 1);
        let report = audit(&wrong);
        assert!(!report.passed);
        assert_eq!(report.disagreements[0].label, "F[w_y]");
        assert_eq!(
            report.disagreements[0].difference.as_deref(),
            Some("2*m2*g*b*sin(phi)")
        );
    }

    #[test]
    fn a_non_finite_entry_is_named_as_such_not_printed_as_a_zero_difference() {
        // 0*log(phi - phi) simplifies to 0 and evaluates to 0*(-inf) = NaN.
        let text = vehicle8_hand().replacen("v_x = 0", "v_x = \"0*log(phi - phi)\"", 1);
        let report = audit(&text);
        assert!(!report.passed);
        let d = &report.disagreements[0];
        assert_eq!(d.label, "F[v_x]");
        assert_eq!(d.non_finite, Some("hand"));
        assert_eq!(d.difference, None);
        let table = report.table();
        assert!(
            table.contains("F[v_x]") && table.contains("not finite"),
            "{table}"
        );
        assert!(!table.contains("F[v_x] = 0"), "{table}");
    }
}
