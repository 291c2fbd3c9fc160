"""The names of a bundle's functions, in the order every bundle lists them, without the
builder: equations.system defines each (DEFINITIONS, checked against this order as it is
imported); backends.deferred names from here the functions a joint tree's bundle leaves for
later on every warm run, which builds none of them."""

NAMES = ("phi", "phi_q", "nu", "gamma", "variations", "phi_scaled", "mass_matrix",
         "generalized_forces", "energy", "reactions", "body_rates", "element_outputs",
         "romega_mass", "romega_forces", "romega_jacobian", "romega_nu", "romega_gamma",
         "romega_q_dot", "romega_to_rp")
