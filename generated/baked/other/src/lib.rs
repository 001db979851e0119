//! The other shipped models with their parameters folded as compile-time constants: `segway7`
//! from `vehicles/segway.toml`, the explicit models from their IR defaults (the tests compare
//! them with the runtime-parameter models bit for bit).

twv_macros::twv_model!(
    ir = "../../ir/segway7.json",
    name = Segway7,
    bake = "../../../vehicles/segway.toml"
);
twv_macros::twv_model!(ir = "../../ir/lorenz.json", name = Lorenz, bake = defaults);
twv_macros::twv_model!(
    ir = "../../ir/henon_heiles.json",
    name = HenonHeiles,
    bake = defaults
);
