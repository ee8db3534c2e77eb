"""The mechanics of a body: kinematics, stress updates, materials and return maps, the quadrature
state, the body and its finite-element model (residual and exact Jacobian)."""
