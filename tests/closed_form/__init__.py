"""The four-bar's and slider-crank's force analysis in closed form: the seed's own member
equilibrium (a 9 × 9 system per pose), friction circle, superposition and virtual work,
written for these two mechanisms alone.

They are an oracle here, not a backend: the harness solves every case, a four-bar
included, with the one linkage engine (:mod:`mechcheck.analytic`), and the tests check that
engine against these independent derivations."""
