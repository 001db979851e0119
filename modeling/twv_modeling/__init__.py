"""twv modeling: multibody descriptions -> Euler-Poincare equations (CasADi) -> model IR."""
