r"""Steady vesicle (inextensible Helfrich membrane, viscosity ratio 1) in a tube, solved directly.

Nondimensionalisation (stated once): tube radius R = 1, outer viscosity eta = 1, mean velocity of
the undisturbed Poiseuille flow U = 1 (:math:`u^\infty = 2(1 - r^2)e_x`). The vesicle has the
volume of a sphere of radius :math:`R_0 = \lambda R` and the area of a sphere of radius
:math:`R_A = R_0\nu^{-1/3}`; bending modulus :math:`\kappa = \lambda^2/\mathrm{Ca}_B` in
:math:`\eta U R^2` (Ca_B = ηUR0²/κ); tension in ηU.

Physics (Chen et al. 2020 §II, eq. E:fm; Pozrikidis 1992): the membrane loads the fluid with
:math:`q = f_b + f_\gamma` (:mod:`bem.membrane`); with equal viscosities the velocity is the
single layer of :math:`q` over the membrane plus the wall and inlet layers of the tube problem
(:mod:`bem.drop`, :mod:`bem.assembly`). In the frame moving with the vesicle a steady,
axisymmetric, inextensible membrane is at rest (r w_s = const = 0 from the poles), so the
steady state is a shape, a tension :math:`\gamma(\tau)` and a speed V with

.. math:: u(X_i) = V e_x \quad\text{at every membrane node (both components)},

volume, area and centroid fixed. Two rows are redundant at the solution (the null vector n of
the single layer and the global area-rate identity): the equations are solved in least squares.

Method:

* shape: :class:`bem.shape.SpectralCurve` with N sine modes of the tangent angle; c_1 closes the
  curve, the length fixes the volume, the shift centres it (as for the drop), and one more mode
  (the ``area_mode``, the one with the largest effect on the area at the start) is solved for so
  that the area is exact. Volume, area and centring therefore hold to round-off.
* tension :math:`\gamma = \sum_{k=0}^{M-1} g_k\cos(k\pi\tau)` and V enter linearly: for each
  shape they are the linear least-squares solution (variable projection, Golub & Pereyra 1973),
  so the nonlinear unknowns are the N - 2 free shape modes.
* the weighted residual :math:`\sqrt{w_i}(u_i - V e_x)` (both components) is minimised by
  Levenberg–Marquardt with a forward-difference Jacobian (its points evaluated concurrently,
  :func:`_residuals`, each at the tension and V of the point it differentiates, the differences
  projected off their columns: the variable-projection Jacobian of Kaufman 1975, whose J^T F is
  the full derivative's, :meth:`VesicleOperator.fixed_residual`) and Broyden updates
  (:func:`bem.newton.levenberg_marquardt`, shared with the drop; a level on the density of the
  level below starts from that level's Jacobian interpolated to its nodes and differences only
  its new modes, :func:`_prolonged_columns`: at (0.9, 1.0) 57 BEM evaluations instead of 113,
  outputs within 3e-8 of the fresh-Jacobian minimum). Long vesicles near lam_c have a slow,
  strongly curved valley of ``|F|`` (volume moved between the caps through the thin film); they
  use :func:`bem.newton.valley_levenberg_marquardt` (directional Jacobian updates,
  extrapolation along the valley), which reaches the minimum where the plain method stops on
  the valley's side (docs/validation.md).
* the wall, inlet and panel breaks are those of :class:`bem.drop.DropOperator`, fixed during one
  solve so that the residual is a smooth function of the modes.

Near the critical confinement (thin film, gap h ≪ R) the velocity is set by the gap to a small
*relative* error along the film and its entrance/exit transitions (length ~ sqrt(hR)), where the
curvature is small: uniform arc length or a curvature-equidistributing density leave a residual
floor ~5e-2 at 16–24 modes (λ/λc = 0.97). ``density="film"`` (the default from λ/λc = 0.9)
builds the arc-length density from the lubrication weight (h + h_min)^(-1/2)
(:func:`bem.shape.film_density`); the panel breaks (graded by sqrt(gap) in τ) then also cluster
there. The quadrature is not the limit (V/U of a fixed shape changes by 1e-7 from 8 to 24
membrane panels at λ/λc = 0.97). A cold start from the lubrication shape at λ/λc = 0.97 drifts
to a spurious, nearly closed film (min gap 1.5e-3); the default continuation in λ/λc (rungs
0.9, 0.95, 0.975, ... below the target) avoids it. Measured at ν = 0.9, Ca_B = 50, 48 modes
(docs/validation.md): λ/λc = 0.95, 0.97, 0.98 reach residuals 3.2e-4, 1.2e-3, 2.9e-3, V/U within
0.04 % and Δp⁺ 6.8, 4.65, 3.2 % above lubrication, in ~4 min per point.

Long vesicles (Chen's length estimate ℓc λ/λc > 5 R, i.e. ν ≲ 0.75 at moderate to high
confinement) have caps, a sharp parachute rim and the junctions where a cap meets the thin film,
each on scales ≪ their length. ``density="bend"`` adds a curvature-gradient term to the
curvature weight (:func:`bem.shape.equidistributing_density`), which resolves all three (fitted
lubrication shape at ν = 0.6, λ/λc = 0.98: relative gap error 1e-4 with 64 modes, against 8e-3
with the curvature weight alone); it is the default for every vesicle that is not near lam_c
(built on a BEM shape it also beats uniform arc length on short ones: at (0.8, 1.0), 40 modes,
residual 2.5e-6 against 8.7e-4).

Ladder and error estimate (automatic refinement, ``n_modes`` None):

* the density is built on a BEM minimum and then kept: on the seed if it is one (``initial``
  a VesicleResult, or the continuation rungs below), else on the shape of a first level solved
  from the lubrication seed (16 modes; for a long vesicle the level ``first`` ≈ 6 modes per R
  of estimated length minus 16, reached through carrier levels 16, 32, ... of one difference
  Jacobian each, which keep the cold start on the physical branch: started at 43–64 modes it
  drifts to a closing film). A density built on the lubrication shape misses the BEM shape's
  rear film neck (at (0.6, 1.94), 64 modes: γ_max 931 instead of the mode-converged 1011).
  A level on that first re-built density still resolves the neck only in part, so a long
  vesicle near lam_c re-builds it once more, on the next level's shape
  (``NEAR_CRITICAL_REBUILDS``; at (0.6, 1.94) the consistent ladder then contracts by
  0.26–0.38 per +8 modes instead of ~0.4 and converges at 88 or 96 modes).
* the levels on that density, +8 modes each, form a consistent ladder: each starts from the
  previous minimum with its Jacobian prolonged (:func:`_prolonged_columns`), and their
  successive differences contract geometrically (spectral convergence; ratios 0.02–0.3 per 8
  modes measured at (0.9, 1.0), (0.8, 1.0), (0.7, 1.5), (0.6, 1.5), (0.6, 1.94)).
* the error estimate of the last level is the tail of that geometric series,
  ``ESTIMATE_SAFETY`` × d ρ/(1 − ρ) from the last two differences, ρ the median of the three
  outputs' contractions (:func:`_error_estimate`);
  the ladder stops at the first level where three consistent levels give an estimate within
  ``tol`` (V/U, Δp⁺) and ``tension_tol`` (γ_max) and the residual is below ``residual_tol``.
  The former estimate, the difference of a pair whose coarse level had another density (long
  vesicles) or 2/3 of the modes, was 10–250 times the true error, and the solve reported "not
  converged" at (0.8, 1.0), (0.6, 1.5) and (0.7, 1.5) with answers right to 1e-5–1e-3.

Seeds and branches. Near lam_c (λ/λc > ``NEAR_CRITICAL`` = 0.9) a vesicle of estimated length
up to ``RUNG_MAX_LENGTH`` = 9 R is reached by continuation in λ/λc (rungs 0.9, 0.95, 0.975,
..., each a ``rung_modes`` = 32 solve from the previous one, the first from lubrication): a
cold start from the lubrication shape at the target can end in a spurious least-squares
minimum (at (0.7, 0.95 λc): residual 2.1e-2 at every mode count, V/U 1.09, Δp⁺ 600, where
the state reached by the rungs has V/U 1.0503, Δp⁺ 403, residual 2.2e-4 at 56 modes;
lubrication 1.0504, 391). Below, the seed is the lubrication shape
at the target or, where the lubrication branch ends above it and λ/λc ≥ 0.5, at 0.9 λc
(:func:`lubrication_seed`). Prolate spheroid and capsule seeds, fore-aft symmetric, can end in
a symmetric least-squares minimum that is not a steady state (at (0.7, 1.2): residual 1.5e-2
at 40–64 modes, V/U 1.386, where the lubrication-anchored seed gives residual 4e-5 at 48 modes,
V/U 1.2591); they remain the last resort, and the residual test reports such a minimum.

Solver paths, before → after (each remaining one with its reason):

* densities: uniform / film / bend chosen by regime, re-built on a BEM shape only for a long
  vesicle's last level → film near lam_c, bend elsewhere, always built on a BEM shape (above);
  re-built once → twice in a row for a long vesicle near lam_c started from its own
  lubrication shape, with five consistent levels up to 48 modes above the first (measured at
  (0.6, 1.94): once, not converged at 88 modes, 1602 BIE solves; twice, converged at 88 or 96
  modes depending on the carriers' path, 1587 or 1745), once elsewhere (a second re-build
  costs the red blood cell (0.61, 0.71 lam_c) a level: 682 BIE solves instead of 454).
* not adopted: a Jacobian carried across a re-built density by the chain rule (mode map by curve
  fits, rows by arc-length fraction) is accurate for the lower half of the modes only (at (0.9,
  1.0), 16 → 24 modes: column errors 0.3–6 %, above it 12–56 %), which would save ~3 % of the BIE
  solves at (0.6, 1.94); ending a valley level once a fresh Jacobian's step achieves 90 % of its
  promised decrease of ``|F|²`` (at (0.6, 1.94): 1358 BIE solves instead of 1745) leaves the 72- and
  80-mode levels 2e-5 (V/U) and 0.1 (Δp⁺) from their certified minima, noise of the size of the
  differences the error estimate extrapolates. Also not adopted: the wall solve by an explicit
  inverse (a product instead of the locked ``lu_solve``; two concurrent evaluations at 96 modes
  of (0.6, 1.94) 0.086 s against 0.080 s); two OpenBLAS threads in an evaluation (0.25 s against
  0.18 s with one, the threads competing with numba's); the load columns of an evaluation that
  runs alone split in two halves on two threads (0.120 s against 0.118 s at 96 modes: the wall
  solve, under the lock, is half the products' time); +16 instead of +8 modes between the
  consistent levels of a long vesicle near lam_c (64, 80, 96 at (0.6, 1.94): 82 s and 1362 BIE
  solves, but the Δp⁺ estimate 1.1e-4 relative, above ``tol``, where the +8 ladder converges at
  96 modes). Measured with the Kaufman Jacobian and not adopted: the level whose shape builds the
  first re-built density of (0.6, 1.94) (48 modes) as a carrier (one difference Jacobian, no
  convergence test): its shape resolves the neck less, and the ladder converged at 96 instead of
  88 modes (1595 BIE solves instead of 1476); the lubrication seed solved to 1e-3 instead of
  ``SEED_LUBRICATION_TOL`` = 1e-4: the same BIE solves at six default cases and 0.4 s less at
  (0.61, 1.39), but (0.6, 1.94) took another path (1788 BIE solves) and ended not converged at 96
  modes (Δp⁺ estimate 1.1e-4 relative). Also not adopted: the products of an evaluation that runs
  alone (the Levenberg–Marquardt steps) split by rows over the two threads, each with one BLAS
  thread (13–17 ms instead of 24–29 ms for the products at 96 modes; default solves 10 % faster
  at the same BIE solves: (0.61, 1.39) 11.0 → 10.0 s, (0.9, 1.0) 1.4 → 1.2 s, (0.7, 1.5) 7.0 →
  6.1 s, (0.6, 1.5) 17 → 15.7 s): the smaller blocks change the BLAS rounding, and (0.6, 1.94)
  took another path that converged at 96 instead of 88 modes, in 81–85 s instead of 67 s.
  Re-measured back to back with the median-rate error estimate: 1–3 % ((0.61, 1.39) 12.3 →
  12.1 s, (0.7, 1.5) 7.5 → 7.4 s; one evaluation at 96 modes of (0.6, 1.94) 109–113 → 105–109
  ms), and (0.6, 1.94) took 1554 BIE solves instead of 1476 (88 modes both).
* wall mesh: the drop's rule, wall panels beside the body following the membrane's panel
  count → the same, lengthened by ``WALL_BODY_LENGTH``/extent beside a vesicle longer than
  6 R, whose panel count grows with its length (at a fixed 64-mode shape of (0.6, 1.94):
  outputs within 4e-9, 1.7 times fewer wall nodes; with 5 R, 0.37 s → 0.20 s per evaluation
  at 88 modes), and following at most ``WALL_BODY_PANELS`` = 16 membrane panels (48 modes;
  outputs within 1e-8 of a wall refined twice, measurements at the constant; the default
  solve at (0.6, 1.94): 165 s → 114 s, the same 1749 BIE solves, outputs within 4e-8).
* Jacobian points: each re-solving the tension and V (M + 1 load columns per BEM solve) → at the
  tension and V of the point differentiated (one load column; Kaufman's variable-projection
  Jacobian, same gradient J^T F; columns within 6e-6 of the full ones at a 24-mode minimum of
  (0.9, 1.0)). Per Jacobian point on 2 threads, (0.61, 1.39) shape: 18 → 16 ms at 32 modes, 29 →
  25 ms at 56, 48 → 39 ms at 88 (the assembly, not the products, is then most of a point). The
  seven default cases (``default_cases.py``, 2 cores): (0.8, 1.0) 4 → 3 s, (0.7, 1.2) 11 → 9 s,
  (0.6, 1.5) 22 → 17 s, (0.7, 1.5) 10 → 7 s, (0.9, 0.98 λc) 33 → 24 s, (0.7, 0.95 λc) 31 → 21 s,
  (0.6, 1.94) 109 → 67 s (1565 → 1476 BIE solves, converged at 88 modes both, estimates 5.4e-5,
  0.047, 3.5 against 5.1e-5, 0.061, 3.7); (0.61, 1.39) about the same (454 → 456 BIE
  solves, 12.6–12.7 s → 12.4–12.8 s back to back: at 56 modes the assembly dominates a
  point). Also measured: fewer tension modes than shape modes (M = N/2) are cheaper per
  evaluation but converge later: (0.7, 1.5) at 64 modes in 17 s instead of 48 in 9 s, (0.61,
  1.39) not converged at 80 modes; M = 3N/2 gains nothing (the same levels, 14.2 s for (0.61,
  1.39)); M = N stays.
* far field of the Jacobian points: each point assembling its own membrane–membrane and
  membrane–wall influence matrices → from ``LINEARISED_POINTS`` = 8 points on, their far pairs
  and the wall's near panels on the membrane nodes expanded to first order in the membrane
  node positions about the state differentiated (:meth:`VesicleOperator.taylor`, once per
  Jacobian), the membrane's near and self panels and the inlet per point, the wall solves of
  all the points in one ``lu_solve``. The linearised residual differs from the exact one at
  second order in the displacement (at 96 modes of (0.6, 1.94): 1.9e-12 … 1.9e-6 for steps
  1e-8 … 1e-5), so at the Jacobian's step 1e-7 its columns are within 1.8e-5 of the largest
  column of exact differences (88-mode seed of (0.6, 1.94); median 5e-8 of a column's own
  norm): these cancel the second-order terms of the two residuals of a difference, the
  linearised points do not (``tests/bem/test_vesicle_linearised.py``). At that seed, per
  point on one thread (Intel Xeon): 95 → 41 ms (the membrane's near panels on the wall 20 ms,
  on itself 16, the loads 6); the expansion 0.16 s per Jacobian. Fewer points (the 3 of a
  directional update) are not worth it: the expansion costs about what 3 points save.
  Default solves on 2 cores, back to back (the machine's speed drifts by 30 % over an hour,
  so each comparison is within one run of pairs): (0.6, 1.94) with exact points 58.6–61.4 s
  (1442 BIE solves, converged at 96 modes), with the far pairs linearised 48.2–50.0 s (1372,
  88 modes); later, the machine slower, the far pairs linearised 63–71 s (1372, 88 modes),
  the wall's near panels too 72–77 s (1485, 96 modes: the rounding of the columns changed the
  carriers' path; estimates 5.8e-5, 0.032, 4.9 → 2.1e-5, 0.029, 1.6 for V/U, Δp⁺, γ_max);
  (0.61, 1.39), the same 448 BIE solves each way: 10.1–10.5 s exact, 9.4–10.0 s far pairs; later
  13.4–15.7 s far pairs, 12.4–12.9 s near panels too. The six other default cases take the
  same BIE solves as with exact points, their outputs move by less than 1e-3 of their
  estimates and their times by the machine's noise (``default_cases.py``).
  The membrane's near and self panels per point → expanded too, in the panels' Legendre
  coefficients and the nodes (:func:`bem.kernels.near_panels_taylor`, the integrand
  differentiated on each pair's rule; derivatives within 2.5e-10 of central differences of
  the integrals), their products with all the points' displacements in one pass
  (:func:`bem.kernels.near_products_taylor`). At the converged 96-mode shape of (0.6, 1.94):
  per point on one thread 54 → 24 ms (curve construction and loads are now most of it), the
  expansion 0.13 → 0.47 s on 2 threads, a 94-point Jacobian 3.3–3.5 → 1.6–1.8 s, its columns
  within 4.5e-6 of the largest column of exact differences (1.4e-5 with only the far pairs
  expanded). Default solves back to back on 2 cores (a slow hour): (0.6, 1.94) 75.1–81.7 s
  (1485 BIE solves, 96 modes) → 61.0–66.7 s (1486, converged at 88 modes: the columns'
  rounding changed the path; estimates 5.9e-5, 0.049, 4.8 for V/U, Δp⁺, γ_max, true errors
  8.6e-6, 7e-4, 1.4 against the mode-converged values); (0.61, 1.39) 15.4–16.6 s → 12.2–13.0 s
  (448 BIE solves both). Also measured and not adopted: the directional updates' points
  linearised about the level's last Jacobian (its base moved by up to 1e-3 since, which
  errs at first order in the directions of the smallest singular values): at (0.6, 1.94) the
  valley stalled, 2672 BIE solves, not converged at 96 modes. With the Jacobians this cheap
  (a 46-point Jacobian at 48 modes costs about three directional updates), measured at
  (0.6, 1.94) and not adopted: a fresh difference Jacobian after every accepted step of the
  valley method instead of the directional updates (54.9 s against 57.3 s, profiled minutes
  apart, 3044 BIE solves, converged at 96 modes; the other valley cases of the default set:
  (0.6, 1.5) 14 → 16 s, the others within the machine's noise); the same on the levels
  started from a prolonged Jacobian only (their Gauss–Newton steps end in 3–4 iterations at
  the floor test, short of the valley's minimum: not converged at 96 modes, V/U estimate
  1.5e-4 relative); 2 or 1 directions per update instead of 3 (on 2 threads the 3 or 2
  points of an update take as long as 4 or cost half; (0.6, 1.94): 1174 or 1167 BIE solves,
  37–46 s against 48–54 s for 1486, but at Ca_B = 50.01 2 directions took 1431 BIE solves
  against 1224 for 3, and with 1 direction the Δp⁺ estimate, 0.016, fell below the true
  error, 0.033).
* the valley method's floor test: a fresh difference Jacobian at every stall → the Jacobian
  differenced at this level certifies when the iterate has moved by less than
  :data:`bem.newton.RECENT_STEP` since (:func:`bem.newton.valley_levenberg_marquardt`). At
  (0.6, 1.94) the levels 72, 80, 88 no longer difference a second Jacobian: 1476 → 1248 BIE
  solves, 71–77 s → 62 s on the same machine, converged at 88 modes both, outputs within 2e-9
  (V/U), 5e-6 (Δp⁺) and 1.5e-4 (γ_max), the same estimates; (0.6, 1.5) 645 → 615 BIE solves;
  (0.7, 1.5) 365 → 343, (0.7, 0.95 λc) (its continuation rungs) 895 → 766 (estimates within
  3.1 times the true errors; ``default_cases.py``);
  (0.6, 1.94) at Ca_B = 50.01 1803 → 1425 (96 modes both, 95 → 73 s); λ = 1.9399 and 1.9401
  converge at 88 modes (1418 and 1524 BIE solves, 68 and 79 s). Measured and not adopted: a
  stall test at 1 % instead of 0.1 % for a Jacobian prolonged from the level below (24 fewer
  BIE solves at (0.6, 1.94), V/U estimate 8.8e-5 instead of 5.4e-5); a fresh difference
  Jacobian, instead of the last carrier's prolonged one, for the first level after a long
  vesicle's carriers (its valley iterations crawl ~30 steps): (0.6, 1.94) with Ca_B = 50 and
  50.01 and at λ = 1.9399 and 1.9401 in 60.2, 68.0, 61.3, 57.4 s against 61.7, 72.9, 67.8,
  78.8 s, but (0.6, 1.5) then stopped at 64 modes with estimates half its true errors
  (3.96e-6 against 7.38e-6 in V/U; ``default_cases.py``), and the benchmark (0.6, 1.94) in
  fresh processes took 62.6 s (1292 BIE solves) against 62.2 s.
* the valley method's Jacobian prolonged from the level below, kept until a step stalls →
  replaced by a difference Jacobian once five steps with it together reduce ``|F|`` by less
  than 2 % (:data:`bem.newton.CRAWL_GAIN`; at (0.6, 1.94) its 48-mode level crawled 48 steps
  of ratio 0.990–0.999 before its first difference Jacobian). It changes only the long
  vesicles near lam_c started from carriers. Measured on 2 cores (BIE solves, modes, s):
  (0.6, 1.94) 1486 → 1351 (88 → 96 modes; estimates 5.9e-5, 0.049, 4.8 → 2.0e-5, 0.026, 1.5
  for V/U, Δp⁺, γ_max; 37.2 → 31.2 s); at Ca_B = 50.01 1224 → 1351 (88 → 96 modes; 7.6e-5,
  0.020, 6.7 → 2.4e-5, 0.030, 1.9; 31.0 → 29.8 s, in another run 29.1 → 32.7 s); λ = 1.9399
  1392 → 1381 (88 modes both; 35.2 → 34.1 s, 35.1 → 39.0 s); λ = 1.9401 1501 → 1484 and
  (0.65, 0.98 λc) 1840 → 1821, not converged at 96 modes either way (estimates 1.4e-4 and
  2.6e-3 relative in V/U). Over these five the BIE solves are about the same (7443 → 7388):
  the gain at (0.6, 1.94) is mostly its path. The six other default cases, (0.6, 1.88),
  (0.6, 1.7), (0.62, 0.97 λc) and (0.55, 0.96 λc) are bitwise unchanged (the rule does not
  fire).
* evaluations: one after the other → the points of a difference Jacobian and of a
  directional update evaluated concurrently, one per numba thread (:func:`_residuals`; the
  assembly serial on each thread, the products concurrent, the LAPACK calls under a lock);
  every point starts its area secant from the same slope, so the result does not depend on
  the thread count (the sequential secant started from the previous point's slope, which
  made the Jacobian columns, and through them the levels' paths, depend on their order).
  Measured on 2 cores, default solves: (0.61, 1.39) 15.3–18.6 s → 13.5 s, (0.6, 1.94)
  228 s → 165 s (before the wall cap).
* curve work (closed curves, sampling, curvatures, bending force): the Clenshaw sums in
  numpy, one array operation per coefficient → in numba (:mod:`bem.series`; at
  (0.61, 1.39) the curve work was 35 % of the solve) → the position integrals from piecewise
  interpolants (:func:`bem.series.pole_integrals`; over a default solve of (0.6, 1.94),
  ``profile_vesicle.py``: 27 449 calls in 20.7 s → 25 024 in 7.4 s of thread time) and a
  Jacobian point's tension load summed from its series (:func:`bem.membrane.tension_force`,
  not from the M-mode basis). The results move by rounding, which changes the unconverged
  carrier levels of (0.6, 1.94) and with them its path: with the bending-force sums in
  numba 1819 BIE solves in 119 s (converged at 96 modes, estimates 4.7e-5, 0.039, 4.1 for
  V/U, Δp⁺, γ_max against true errors 5.9e-6, 0.005, 1.1); with the
  position integrals in numba too 1565 BIE solves in 107 s (converged at 88 modes,
  estimates 5.1e-5, 0.061, 3.7 against 6.8e-6, 0.002, 1.3). Which level converges is
  decided by the unconverged carriers, not by the physics: compare BIE solves and error
  estimates, not single timings.
* refinement: plain ladder to a pair (short), carriers + cross-density pair (long), pair
  (2n/3, n) (given ``n_modes``) → one consistent ladder with an extrapolated estimate; the
  carriers stay for a long vesicle's cold start, the pair for a given ``n_modes`` (its
  estimate is the pair difference, an overestimate).
* error estimate: each output extrapolated with its own contraction → with the median of the
  three outputs' contractions (:func:`_error_estimate`): at (0.6, 1.94), Ca_B = 50.01, the
  default solve ended not converged at 96 modes (Δp⁺ estimate 1.2e-4 relative, its own ratio
  0.66) and now converges there (3.0e-5; 1803 BIE solves, 95 s); the seven default cases stop
  at the same levels (``default_cases.py``), and the estimates move where an output's ratio
  was the outlier: γ_max at (0.8, 1.0) 7.7e-6 → 3.6e-6 (now 9.6 times the true error, was 21),
  at (0.9, 0.98 λc) 0.15 → 0.057, at (0.7, 0.95 λc) 1.1 → 0.60 (6.2 times, was 11.9); Δp⁺ at
  (0.9, 0.98 λc) 6.8e-3 → 7.8e-3, at (0.7, 0.95 λc) 9.4e-3 → 2.0e-2 (2.2 times the true error,
  was 1.05), at (0.6, 1.94) 0.047 → 0.049, and γ_max there 3.5 → 4.3 (measured before the
  valley floor test above changed the paths).
* continuation rungs: short vesicles near lam_c only (ℓ ≤ 5) → vesicles near lam_c up to
  ℓ = 9 (``RUNG_MAX_LENGTH``; longer ones from their own lubrication shape, measured above).
  Measured and not adopted (yet): every long vesicle (ℓ > 5) near lam_c from its own
  lubrication shape through carrier levels. At Ca_B = 50 (rungs → carriers; BIE solves,
  modes or "not converged"): ℓ = 5.3 (0.8, 0.98 λc) 1286, not converged → 985, not converged
  (Δp⁺ estimate 9.4e-4 → 1.3e-4 relative); 5.7 (0.78, 0.98 λc) 1315, not converged → 1084,
  72; 6.2 (0.75, 0.97 λc) 964, not converged → 691, 64; 7.0 (0.72, 0.98 λc) 1290, not
  converged → 1021, not converged (V/U 1.7e-3 → 2.7e-5); 7.0 (0.7, 0.92 λc) 372, 48 → 476,
  56 (V/U estimate 6.4e-6 → 1.0e-7); 7.5 (0.7, 0.98 λc) 1386, not converged → 1010, 72;
  8.0 (0.68, 0.97 λc) 1129, 64 → 719, 64; 8.4 (0.67, 0.98 λc) 1314, not converged → 1038,
  72; 8.6 (0.66, 0.97 λc) 1086, 72 → 900, 64; 8.7 (0.65, 0.95 λc) 737, 64 → 626, 72
  (residual 3.7e-4 → 3.7e-6); 9.0 (0.65, 0.98 λc) 1840, not converged → 1010, 80. Where
  both converge the outputs agree within the larger estimate; the spurious minimum for
  which (0.7, 0.95 λc) was given the rungs (residual 2.1e-2) no longer occurs (633 → 580 BIE
  solves, 56 modes both, residual 3.9e-4 → 4.8e-5, Δp⁺ true error 8.1e-3 → 1.2e-4). Not
  adopted because there the Δp⁺ estimate, 3.1e-5, falls below that true error: the error of
  the 56-mode level is its Levenberg–Marquardt stop (the floor test's ``promise`` 1e-2), not
  the modes (with ``promise`` 1e-4 on every level: error 3.0e-6, estimate 3.0e-4, 745 BIE
  solves). The error estimate has no term for that stop yet; the outputs' change along the
  Gauss–Newton step of the level's final Jacobian does not reveal it (Δp⁺ −2.5e-7 there).
* Levenberg–Marquardt: plain, or the valley variant for long vesicles (kept: the plain method
  stops on the valley's side, γ_max 799 instead of 932 at (0.6, 1.94), 64 modes); the
  prolonged Jacobian now serves both (before: plain only).
* seeds: lubrication → spheroid → capsule, into lubrication at the target → lubrication at
  0.9 λc → spheroid → capsule (above). The lubrication shape is now moved to the centroid
  x = 0 where the solver keeps every shape (:func:`fit_lubrication`): it started at x = 0, and
  the first level's wall, whose finest panels follow the seed, was fine beside the front half
  of the vesicle only (at (0.6, 1.94) panels 0.36–2.7 R long beside the rear film). Measured
  with ``default_cases.py`` (paths, not only times, change): (0.6, 1.94) 1477 → 1464 BIE
  solves, 96 modes both, estimates 4.4e-5, 0.018, 3.7 → 1.7e-5, 0.026, 1.25, residual 1.8e-4
  → 1.25e-4; (0.7, 1.2) 414 → 402, (0.7, 1.5) 343 → 308, (0.7, 0.95 λc) 766 → 633, but
  (0.6, 1.5) 615 → 700 (72 instead of 64 modes); estimates within 1–10 times the true errors
  as before, except the three pairs of docs/validation.md.
* three fallbacks, each met by the map build: a given initial shape that cannot start at the
  target (its film closes once the volume is re-imposed: (0.98, 0.98 λc) from the 0.95 λc
  shape) is replaced by the solver's own seed; a re-built density that the next level cannot
  carry ((0.95, 0.2 λc): no positive volume at 24 modes) is dropped for the seed's; a seed
  density the first level cannot carry ((0.85, 0.2 λc), "bend" on the lubrication shape)
  is replaced by uniform arc length.

Resource envelope (checked before any BEM work by :func:`check_vesicle_inputs`):

* shape modes 8 <= n_modes, max_modes, rung_modes <= :data:`MAX_MODES` = 96 (the long vesicle at
  (0.6, 0.98 λc) needs 88–96; a level of N modes has max(8, ceil(N/3)) panels and a difference
  Jacobian costs N BEM evaluations, ~0.02–0.08 s each (one load column), two at a time on 2
  cores, so 96 modes is ~5 s per Jacobian); peak memory stays below 1 GB (measured 553 MB for the
  default solve at (0.6, 0.98 λc), two evaluations at a time; 839 MB one at a time before the
  wall followed at most WALL_BODY_PANELS, 1.5 GB before the wall beside long vesicles was
  lengthened).
* :data:`CA_B_MIN` = 0.01 <= Ca_B <= :data:`CA_B_MAX` = 1e5, the range of the lubrication
  solver that provides the initial shape (:mod:`lubrication.solve`; at 1e5 bending is within
  1e-6 of the high-Ca model). Ca_B = ηUR0²/κ is ~1–1000 for red blood cells (Chen et al.
  2020 use 50). Measured at (0.9, 1.0), 16 modes: Ca_B = 0.01 converges in 21 s; Ca_B = 1e308
  (bending load ~1e-308) used to run to a failed solve.
* ``max_time`` (:class:`lubrication.checks.Deadline`) is tested between BEM evaluations of
  Levenberg–Marquardt, between levels and between continuation rungs; when spent the result
  has status TIME_LIMIT and the deadline's message. Each level does at most ``max_iter``
  (40; valley: 320) iterations and 4–8 difference Jacobians.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext

import numpy as np
import scipy.linalg as sla
from scipy.interpolate import CubicSpline
from scipy.optimize import minimize_scalar

from lubrication.checks import Deadline, InvalidParameterError, check_positive, check_range
from lubrication.geometry import critical_confinement, critical_length, resolve_confinement
from lubrication.results import LubricationResult, Status, leading_status
from lubrication.solve import solve_lubrication

from .assembly import poiseuille
from .drop import DropDiscretisation, DropOperator, panels_for
from .drop import mode_count as _drop_mode_count  # one check, the vesicle's MAX_MODES
from .membrane import bending_force, tension_basis, tension_force, tension_profile
from .newton import difference_jacobian, levenberg_marquardt, valley_levenberg_marquardt
from .quadrature import (
    DEFAULT_ORDER,
    assembles_serially,
    barycentric_weights,
    gauss_legendre,
    gauss_table,
    influence,
    influence_pair,
    near_factor,
    self_rule,
    self_rule_panels,
    serial_assembly,
)
from .results import VesicleResult
from .seed_bank import SHAPE_CLASSES, load_seed_bank
from .shape import (
    SpectralCurve,
    equidistributing_density,
    film_density,
    fit_curve,
    spheroid_curve,
)
from .threads import single_threaded_blas

__all__ = ["CA_B_MAX", "CA_B_MIN", "MAX_MODES", "NEAR_CRITICAL", "WALL_REFINEMENT",
           "check_vesicle_inputs", "VesicleOperator", "capsule_seed",
           "fit_lubrication", "level_function", "lubrication_seed", "mode_convergence",
           "seed_from_lubrication",
           "solve_vesicle", "spheroid_seed", "vesicle_discretisation"]

log = logging.getLogger(__name__)

_EIGHT_PI = 8.0 * math.pi

#: most shape modes of one level (resource envelope, module docstring)
MAX_MODES = 96
#: bending capillary numbers accepted (module docstring)
CA_B_MIN, CA_B_MAX = 1e-2, 1e5


# ---------------------------------------------------------------------------- operator
#: held around the LAPACK calls of an evaluation: two threads evaluating shapes at once
#: (:func:`_residuals`) gave wrong wall densities from concurrent ``lu_solve`` calls on one
#: factorisation (scipy 1.17, OpenBLAS 0.3.30: errors of order one; with the lock, or
#: sequentially, identical results); the products between them run concurrently
_LAPACK = threading.Lock()

#: relative singular-value cutoff of the tension/V least squares (gelsy's rcond)
LSTSQ_COND = 1e-13


class VesicleOperator(DropOperator):
    """Velocity of a membrane of given shape in the tube, tension and V by least squares.

    Wall, inlet, panel breaks and density are fixed from ``reference`` (as for the drop).
    ``n_tension`` cosine terms of the tension; ``area_mode`` the index of the mode solved for
    the area (default: the free mode with the largest area derivative at ``reference``).
    """

    def __init__(self, nu: float, lam: float, ca_b: float, disc: DropDiscretisation,
                 reference: SpectralCurve, n_tension: int | None = None,
                 area_mode: int | None = None):
        super().__init__(lam, 1.0, disc, reference)
        self.nu = float(nu)
        self.ca_b = float(ca_b)
        self.kappa = self.lam**2 / self.ca_b
        self.area = 4.0 * math.pi * (self.lam * self.nu ** (-1.0 / 3.0)) ** 2
        self.n_tension = int(n_tension or disc.n_modes)
        modes = reference.with_modes(disc.n_modes)
        self.area_mode = self._pick_area_mode(modes) if area_mode is None else int(area_mode)
        self._area_slope = 0.0                      # dA/dc of the last secant (curve)

    def _raw_curve(self, modes) -> SpectralCurve:
        return SpectralCurve.closed(modes, volume=self.volume, centroid=0.0,
                                    density=self.density)

    def _pick_area_mode(self, modes) -> int:
        base = self._raw_curve(modes).area()
        best, j_best = -1.0, 1
        for j in range(1, min(modes.size, 6)):
            m = modes.copy()
            m[j] += 1e-6
            d = abs(self._raw_curve(m).area() - base)
            if d > best:
                best, j_best = d, j
        return j_best

    def curve(self, modes, slope: float | None = None) -> SpectralCurve:
        """Closed, centred curve of the vesicle's volume and area; ``modes[area_mode]`` is
        replaced by the value that gives the area (secant iteration from the given value, its
        first step with the slope dA/dc ``slope``, default that of the previous call; a given
        slope is not stored, so that concurrent calls do not depend on each other)."""
        m = np.array(modes, dtype=float)
        j = self.area_mode
        x0 = m[j]
        c = self._raw_curve(m)
        f0 = c.area() - self.area
        if abs(f0) < 1e-14 * self.area:
            return c
        keep = slope is None
        slope = self._area_slope if keep else slope
        x1 = x0 - f0 / slope if slope else x0 + 1e-4 * max(1.0, abs(x0))
        for _ in range(40):
            m[j] = x1
            c = self._raw_curve(m)
            f1 = c.area() - self.area
            if abs(f1) < 1e-14 * self.area:
                if keep and f1 != f0 and x1 != x0:
                    self._area_slope = (f1 - f0) / (x1 - x0)
                return c
            if f1 == f0:
                break
            x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
        raise InvalidParameterError("modes", "a shape whose area cannot be adjusted",
                                    "a shape near the vesicle's area")

    def _dependent(self) -> list[int]:
        """c_1 closes the curve, the area mode gives the area."""
        return [0, self.area_mode]

    def velocity_columns(self, curve: SpectralCurve):
        r"""Membrane velocity as an affine function of the tension coefficients (one BEM solve).

        Returns (panels, u0, U, dp0, dp) with the velocity at the nodes (interleaved x, r;
        lab frame) :math:`u = u_0 + U g` for tension :math:`\gamma = \sum_k g_k\cos(k\pi\tau)`,
        and Δp⁺R/(ηU) :math:`= dp_0 + dp\cdot g` (reciprocal theorem, as for the drop).
        """
        return self._columns(curve)[:5]

    def wall_shear(self, curve: SpectralCurve, g) -> tuple[np.ndarray, np.ndarray]:
        r"""Shear stress of the fluid on the tube wall, :math:`\tau_w(x)` [ηU/R], at the wall
        nodes (x, tau_w): the Poiseuille value 4 minus the axial wall density of the disturbance
        (the force per area the wall exerts on the fluid, :mod:`bem.assembly`). Force balance
        on the fluid in the tube (the membrane load has zero resultant):
        :math:`\int(\tau_w - 4)\,2\pi R\,dx = \pi R^2\Delta p^+`. The wall shear rate is
        :math:`\tau_w/\eta` [U/R]."""
        qw = self._columns(curve)[5]
        q = qw[:, 0] + qw[:, 1:] @ np.asarray(g, dtype=float)
        return self.wall.x.ravel(), 4.0 - q[0::2]

    def _loads(self, curve: SpectralCurve, g=None):
        """Membrane panels and the load columns Q (interleaved x, r; bending force, then the
        tension modes) with their Δp⁺ columns; with tension coefficients ``g``, the one column
        of the total load (bending plus that tension)."""
        drop = self.panels(curve)
        if np.max(drop.r) >= 1.0 - 1e-6:
            raise InvalidParameterError("shape", "a membrane touching the wall (closing film)",
                                        "a vesicle inside the tube (max r < 1)")
        tau = self.tau.ravel()
        nd = tau.size
        fb = bending_force(curve, tau, self.kappa)
        if g is None:
            T = tension_basis(curve, tau, self.n_tension)               # (M, 2, nd)
            Q = np.empty((2 * nd, self.n_tension + 1))
            Q[0::2, 0], Q[1::2, 0] = fb
            Q[0::2, 1:], Q[1::2, 1:] = T[:, 0].T, T[:, 1].T
        else:
            ft = tension_force(curve, g, tau)
            Q = np.empty((2 * nd, 1))
            Q[0::2, 0], Q[1::2, 0] = fb[0] + ft[0], fb[1] + ft[1]
        rb, wb = drop.r.ravel(), drop.w.ravel()
        dp = -4.0 * (rb * (1.0 - rb * rb) * wb) @ Q[0::2]                # per column
        return drop, Q, dp

    def _flow(self, drop, Q, dp):
        """Membrane velocity (interleaved, without the Poiseuille flow) of the load columns Q
        with Δp⁺ columns dp, and the wall densities."""
        tol = self.disc.quad_tol
        rb = drop.r.ravel()
        # membrane on itself; membrane on the wall and wall on the membrane in one pass (the
        # ring Stokeslet is reciprocal: one kernel call per far node pair)
        S_dd = influence(drop.x.ravel(), rb, drop, tol=tol)
        S_wd, B = influence_pair(self.wall, drop, tol=tol)
        inl = influence(drop.x.ravel(), rb, self.inlet, tol=tol)
        col_dp = inl[:, 0::2].sum(axis=1) / _EIGHT_PI
        rhs = (S_wd @ Q) / _EIGHT_PI + np.outer(self.col_dp_wall, dp)
        with _LAPACK:
            qw = -sla.lu_solve(self.lu_wall, rhs, check_finite=False)
        return (S_dd @ Q) / _EIGHT_PI + (B @ qw) / _EIGHT_PI + np.outer(col_dp, dp), qw

    def _columns(self, curve: SpectralCurve):
        """velocity_columns plus the wall density columns (2 n_wall, M + 1)."""
        drop, Q, dp = self._loads(curve)
        Uc, qw = self._flow(drop, Q, dp)
        u0 = Uc[:, 0].copy()
        u0[0::2] += poiseuille(drop.r.ravel())
        return drop, u0, Uc[:, 1:], float(dp[0]), dp[1:], qw

    def evaluate(self, curve: SpectralCurve) -> dict:
        """Flow of the membrane ``curve``: the least-squares tension and V, the residual."""
        drop, u0, Ug, dp0, dpg = self.velocity_columns(curve)
        nd = drop.r.size
        wb = drop.w.ravel()
        sw = np.repeat(np.sqrt(wb), 2)
        ex = np.zeros(2 * nd)
        ex[0::2] = 1.0
        M = np.column_stack([Ug, -ex]) * sw[:, None]
        with _LAPACK:
            sol, *_ = sla.lstsq(M, -u0 * sw, cond=LSTSQ_COND, lapack_driver="gelsy")
            self.evaluations += 1
        F = u0 * sw + M @ sol
        g, V = sol[:-1], float(sol[-1])
        res = F / sw
        return {"curve": curve, "panels": drop, "F": F, "g": g, "V": V, "M": M,
                "dp": float(dp0 + dpg @ g), "residual": float(np.max(np.abs(res))),
                "res_x": res[0::2], "res_r": res[1::2]}

    def fixed_residual(self, curve: SpectralCurve, g, V: float) -> np.ndarray:
        r"""Weighted residual :math:`\sqrt{w_i}(u_i - V e_x)` of ``curve`` with the tension
        coefficients ``g`` and speed ``V`` held fixed: one BEM solve of the single load
        :math:`Q[1; g]` instead of the M + 1 columns of :meth:`evaluate` (the assembly, the
        same for both, is then most of the cost: 39 against 48 ms per point at 88 modes on 2
        threads). Its differences, projected off the range of the tension and V columns,
        are the variable-projection Jacobian of Kaufman (1975) (:func:`bem.newton.
        difference_jacobian`)."""
        drop, Q, dp = self._loads(curve, g)
        u, _ = self._flow(drop, Q, dp)
        u = u[:, 0]
        u[0::2] += poiseuille(drop.r.ravel()) - V
        with _LAPACK:                        # the lock also guards the counter (threads)
            self.evaluations += 1
        return u * np.repeat(np.sqrt(drop.w.ravel()), 2)

    def taylor(self, base) -> dict:
        """The influence of a membrane expanded about its panels ``base`` (a state's
        ``panels``) to first order in its geometry, for :meth:`linearised_residual` and
        :meth:`linearised_finish`: the near pairs (membrane on itself, wall and membrane on
        each other; as :func:`bem.quadrature.influence` classifies them at ``base``), the far
        entries with their derivatives in the membrane node positions
        (:func:`bem.kernels.cross_far_taylor`, :func:`bem.kernels.self_far_taylor`: 5 and 7
        ring Stokeslets per far pair), the wall's near panels on the membrane nodes with
        their derivatives in those nodes (:func:`bem.kernels.near_target_taylor`: 5 graded
        integrals per pair) and the membrane's near panels on the wall nodes and on its own
        nodes with their derivatives in the panels' Legendre coefficients and the nodes
        (:func:`bem.kernels.near_panels_taylor`: the integrand differentiated on the rule of
        each pair, 7 ring Stokeslets per quadrature point), once for all the points."""
        from . import kernels  # lazy: numba

        wall = self.wall
        nw, nb = wall.n_nodes, base.n_nodes
        xb, rb = base.x.ravel(), base.r.ravel()
        near = near_factor(self.p, self.disc.quad_tol)
        near_ab = np.empty((nw, base.n_panels), dtype=bool)
        kernels.near_flags(wall.x.ravel(), wall.r.ravel(), base.x, base.r, base.w, near,
                           near_ab)
        near_ba = np.empty((nb, wall.n_panels), dtype=bool)
        kernels.near_flags(xb, rb, wall.x, wall.r, wall.w, near, near_ba)
        near_dd = np.empty((nb, base.n_panels), dtype=bool)
        kernels.near_flags(xb, rb, base.x, base.r, base.w, near, near_dd)
        A_ab = np.zeros((2 * nw, 6 * nb))
        A_ba = np.zeros((6 * nb, 2 * nw))
        A_dd = np.zeros((2 * nb, 8 * nb))
        serial = assembles_serially(nw * nb)
        (kernels.cross_far_taylor_serial if serial else kernels.cross_far_taylor)(
            wall.x, wall.r, wall.w, base.x, base.r, near_ab, near_ba, A_ab, A_ba)
        (kernels.self_far_taylor_serial if serial else kernels.self_far_taylor)(
            base.x, base.r, near_dd, A_dd)
        fixed = self_rule_panels(base, self.disc.quad_tol)
        pairs = {k: np.argwhere(v).astype(np.int64)
                 for k, v in (("ab", near_ab), ("ba", near_ba), ("dd", near_dd))}
        n_ba, p = pairs["ba"].shape[0], self.p
        acc_ba = [np.empty((n_ba, p, 4)) for _ in range(3)]
        tn, _ = gauss_legendre(p)
        gx, gw = gauss_table()
        bw = barycentric_weights(p)
        tol = self.disc.quad_tol
        kernels.near_target_taylor(pairs["ba"], xb, rb, wall.x, wall.r, wall.w, wall.cx,
                                   wall.cr, tn, bw, gx, gw, tol, *acc_ba)
        near = {}
        for key, tx, tr, own in (("ab", wall.x.ravel(), wall.r.ravel(), False),
                                 ("dd", xb, rb, True)):
            n = pairs[key].shape[0]
            near[key] = (np.empty((n, p, 4)), np.empty((n, p, 4, 2 * p + 2)))
            kernels.near_panels_taylor(pairs[key], tx, tr, own, base.x, base.r, base.w,
                                       base.cx, base.cr, fixed, tn, bw, gx, gw, tol,
                                       *self_rule(p), *near[key])
        return {"base": base, "A_ab": A_ab, "A_ba": A_ba, "A_dd": A_dd, "pairs": pairs,
                "fixed": fixed, "acc_ba": acc_ba, "near": near}

    def linearised_residual(self, curve: SpectralCurve, g, V: float, taylor: dict) -> dict:
        r"""The part of :meth:`fixed_residual` that each point needs on its own: the loads,
        the displacements of the membrane's nodes and panel curves from ``taylor``'s and the
        inlet; the influence matrices and the wall solve of all the points are left to
        :meth:`linearised_finish`. Returns the pieces it needs."""
        drop, Q, dp = self._loads(curve, g)
        base = taylor["base"]
        q = Q[:, 0]
        xb, rb = drop.x.ravel(), drop.r.ravel()
        dx, dr = xb - base.x.ravel(), rb - base.r.ravel()
        inl = influence(xb, rb, self.inlet, tol=self.disc.quad_tol)
        u = inl[:, 0::2].sum(axis=1) * dp[0] / _EIGHT_PI
        u[0::2] += poiseuille(rb) - V
        return {"u": u, "q": q, "v": np.repeat(drop.w.ravel(), 2) * q, "dp": float(dp[0]),
                "dx": dx, "dr": dr, "dcx": drop.cx - base.cx, "dcr": drop.cr - base.cr,
                "sw": np.repeat(np.sqrt(drop.w.ravel()), 2)}

    def linearised_finish(self, taylor: dict, parts: list) -> list:
        r"""Weighted residuals of the points of :meth:`linearised_residual` (None where a
        point is None): every influence entry of each moved membrane is that of ``taylor``
        plus its derivatives times the displacements (exact to second order in the
        displacements; for a difference Jacobian, steps ~1e-7), all points in a few products,
        one pass through the near blocks (:func:`bem.kernels.near_products_taylor`) and one
        wall solve."""
        from . import kernels  # lazy: numba

        ok = [k for k, pt in enumerate(parts) if pt is not None]
        out = [None] * len(parts)
        if not ok:
            return out
        pts = [parts[k] for k in ok]
        V = np.column_stack([pt["v"] for pt in pts])
        moved = {k: np.stack([pt[k] for pt in pts]) for k in ("q", "dx", "dr", "dcx", "dcr")}
        DX = np.repeat(moved["dx"].T, 2, axis=0)
        DR = np.repeat(moved["dr"].T, 2, axis=0)
        n2 = V.shape[0]
        # the near blocks of the membrane (on the wall nodes, on its own nodes) of every point
        still = np.zeros((len(pts), self.wall.n_nodes))               # the wall does not move
        near = {"ab": np.zeros((len(pts), 2 * self.wall.n_nodes)),
                "dd": np.zeros((len(pts), n2))}
        for key, dtx, dtr in (("ab", still, still), ("dd", moved["dx"], moved["dr"])):
            kernels.near_products_taylor(
                taylor["pairs"][key], *taylor["near"][key], moved["dcx"], moved["dcr"], dtx,
                dtr, moved["q"], min(_workers(), len(pts)), near[key])
        X = np.vstack([V, DX * V, DR * V])
        rhs = taylor["A_ab"] @ X
        rhs += near["ab"].T
        rhs /= _EIGHT_PI
        rhs += np.outer(self.col_dp_wall, [pt["dp"] for pt in pts])
        with _LAPACK:
            qw = -sla.lu_solve(self.lu_wall, rhs, check_finite=False)
            self.evaluations += len(pts)
        Y = taylor["A_ba"] @ qw
        U = Y[:n2] + DX * Y[n2:2 * n2] + DR * Y[2 * n2:]
        A = taylor["A_dd"]
        U += A[:, :3 * n2] @ X - DX * (A[:, n2:2 * n2] @ V) + DR * (A[:, 3 * n2:] @ V)
        U /= _EIGHT_PI
        pba, p = taylor["pairs"]["ba"], self.p
        for c, (k, pt) in enumerate(zip(ok, pts)):
            u = [np.zeros(n2) for _ in range(3)]
            for acc, uc in zip(taylor["acc_ba"], u):
                kernels.near_product(pba, acc, p, qw[:, c], uc)
            u = u[0] + DX[:, c] * u[1] + DR[:, c] * u[2]
            out[k] = (pt["u"] + U[:, c] + (u + near["dd"][c]) / _EIGHT_PI) * pt["sw"]
        return out


def _range_projector(M: np.ndarray):
    """X -> X minus its projection on the range of M (rank as in the least squares of
    :meth:`VesicleOperator.evaluate`, singular values above LSTSQ_COND of the largest)."""
    U, sv, _ = np.linalg.svd(M, full_matrices=False)
    U = U[:, sv > LSTSQ_COND * sv[0]]
    return lambda X: X - U @ (U.T @ X)


#: wall panels of the vesicle meshes, relative to the drop's rule
#: (``DropDiscretisation.wall_refinement``): the single layer on the wall is smooth on the scale
#: of the membrane panels, and a 4x coarser wall than the drop's changes V/U and Δp⁺ by < 1e-7
#: (relative) at (ν, λ) = (0.9, 1.0) and (0.6, 0.98 λc) while cutting the wall factorisation ~15x
#: (validation.md).
#: 0.15 would change them by ≤ 6e-9 more, but leaves a 6e-5 error in the wall shear at the
#: ends of the meshed tube (Poiseuille there), so the wall stays at 0.25
WALL_REFINEMENT = 0.25

#: axial extent [R] above which the wall panels beside the vesicle are lengthened by
#: WALL_BODY_LENGTH/extent (:func:`bem.drop._wall_and_inlet`): the drop's rule ties them to the
#: membrane's panel count, which for a long vesicle grows with its length, not with the
#: resolution the wall needs. Measured at a fixed shape of (0.6, 0.98 lam_c), extent 10.8 R
#: (outputs of V/U, Δp⁺, γ_max against the unscaled wall): 48 modes 4.5e-8, 88 modes 2e-9
#: relative with 5 R, wall shear at the tube ends unchanged, half the wall nodes and
#: evaluation time; with 2.5 R the change is 9e-6 at 48 modes. 6 R keeps a factor 2.4 from
#: that and leaves the wall of the red blood cell (0.61, 1.39) as it was (extent 5.0 R, its
#: lubrication seed 5.2 R): with 5 R its outputs moved by 1.6e-9 but its carrier levels took
#: another path, 566 BIE solves instead of 454
WALL_BODY_LENGTH = 6.0

#: membrane panel count above which the wall panels beside the vesicle stop following it
#: (:attr:`bem.drop.DropDiscretisation.wall_body_panels`): the wall's share of the error is
#: already far below the ladder's there. Measured on fixed shapes at Ca_B = 50 against a wall
#: refined twice (outputs V/U, Δp⁺, γ_max, relative): with 16, (0.6, 0.98 lam_c) 64 / 96 modes
#: ≤ 7.8e-9 / 9.3e-10 (unlimited: 3.8e-9 / 1.7e-10), and ≤ 3.5e-9 on the stored map shapes
#: (0.9, 0.98 lam_c), (0.7, 0.95 lam_c), (0.6, 0.8 lam_c), (0.6, 0.95 lam_c) at their own mode
#: count and 80 modes; the largest wall shear on the nodes moves by up to 5.8e-4 (sampling of
#: its peak; 6.7e-5 unlimited). One evaluation at 96 modes of (0.6, 0.98 lam_c): 0.21 s → 0.14
#: s (wall nodes 1792 → 976). Re-measured with 14 on the default 96-mode minimum of (0.6,
#: 1.94) against 32: 3.1e-10 (V/U), 2.6e-10 (Δp⁺), residual (a maximum over the nodes) 1.257e-4
#: against 1.247e-4; wall nodes 992 → 880, a Jacobian point at 96 modes 108–116 → 103.5 ms
#: on one thread (55–60 → 53–58 ms with two, back to back); the six shorter default cases take
#: the same levels and BIE solves (``default_cases.py``). With 12 (768 nodes) the outputs still
#: agree to 2.2e-9, but the residual rose to 1.336e-4, and at the stored 64-mode shape by
#: 2.6e-6 (the test bound is 1e-7); with 8 it rose to 4.7e-4
WALL_BODY_PANELS = 14


def vesicle_discretisation(n_modes: int, order: int = DEFAULT_ORDER,
                           n_panels: int | None = None) -> DropDiscretisation:
    """Resolution of a vesicle level with ``n_modes`` shape modes (panels as for the drop: one
    per three modes; measured and not adopted, one per four modes: a Jacobian point at 96
    modes of (0.6, 1.94) 65 → 54 ms, outputs at its fixed minimum within 1.7e-8, but the
    default solve of (0.7, 0.95 lam_c) then ended with a γ_max estimate of half its true
    error, 0.075 against 0.137, ``default_cases.py``)."""
    return DropDiscretisation(n_modes=n_modes, n_panels=n_panels or panels_for(n_modes),
                              order=order, wall_refinement=WALL_REFINEMENT,
                              wall_body_length=WALL_BODY_LENGTH,
                              wall_body_panels=WALL_BODY_PANELS)


# ---------------------------------------------------------------------------- initial shapes
#: BVP tolerance of the lubrication solution that seeds a solve: the seed is a fit with 16-24
#: modes, far coarser; against the default 1e-7, V/U changes by < 1e-8 at (0.9, 1.0),
#: (0.61, 1.39) and (0.6, 1.94) while the solve of (0.61, 1.39) takes 2.4 s instead of 6.3 s
#: (a continuation in lam/lam_c with fewer mesh nodes)
SEED_LUBRICATION_TOL = 1e-4

#: lam/lam_c from which a failed lubrication seed is replaced by the lubrication shape at
#: NEAR_CRITICAL lam_c (:func:`lubrication_seed`); below, the spheroid: measured, (0.7, 0.69
#: lam_c) needs the anchored shape, while at (0.95, 0.2 lam_c) the anchored shape could not be
#: carried to 24 modes (its curve did not close) where a spheroid seed converges
LUBRICATION_ANCHOR_FROM = 0.5

def lubrication_seed(nu: float, lam: float, ca_b: float, n_modes: int,
                     density: str = "uniform", density_terms: int = 16,
                     max_time: float | None = None):
    """Spectral curve fitted to the lubrication solution at (nu, lam, ca_b) (see
    :func:`seed_from_lubrication`) or, where the lubrication branch ends above lam (e.g. at
    lam/lam_c = 0.875 for nu = 0.7, Ca_B = 50) and lam/lam_c >= LUBRICATION_ANCHOR_FROM, at
    lam/lam_c = NEAR_CRITICAL: its shape, with
    the volume re-imposed at lam by the solver, is on the branch of the genuine steady state
    (at (0.7, 1.2): residual 3.8e-5 at 48 modes, geometric convergence), where a prolate
    spheroid or a capsule ends in a fore-aft symmetric least-squares minimum that is not a
    steady state (residual 1.5e-2 at every mode count from 40 to 64). None if the solver
    fails (or runs out of ``max_time`` seconds) or the fit is rejected. Returns (curve,
    lubrication result), the latter solved to the BVP tolerance ``SEED_LUBRICATION_TOL``."""
    deadline = Deadline(max_time)
    lub = None
    for target in (lam, NEAR_CRITICAL * critical_confinement(nu)):
        if lub is not None and (lub.success or target <= lam or deadline.expired()
                                or lam < LUBRICATION_ANCHOR_FROM * target / NEAR_CRITICAL):
            break
        try:
            lub = solve_lubrication(nu, target, ca_b=ca_b, tol=SEED_LUBRICATION_TOL,
                                    max_time=deadline.remaining())
        except InvalidParameterError as exc:         # outside the lubrication model's range
            log.info("no lubrication seed: %s", exc)
            return None, None
    if not lub.success:
        return None, lub
    return seed_from_lubrication(lub, n_modes, density, density_terms), lub


def seed_from_lubrication(lub, n_modes: int, density: str = "uniform",
                          density_terms: int = 16) -> SpectralCurve | None:
    """``n_modes`` fit of a converged lubrication shape with the arc-length ``density`` (a key
    of ``_DENSITIES`` or "uniform", built from a 128-mode fit); None if the fit closes more
    than half of the lubrication gap (a sharp parachute rim the modes cannot carry)."""
    dens = (() if density == "uniform"
            else _DENSITIES[density](fit_lubrication(lub, 128), density_terms))
    curve = fit_lubrication(lub, n_modes, dens)
    gap = 1.0 - float(np.max(lub.r))
    if 1.0 - curve.max_radius() < 0.5 * gap:
        log.info("lubrication seed rejected: %d-mode %s fit has gap %.3g (lubrication %.3g)",
                 n_modes, density, 1.0 - curve.max_radius(), gap)
        return None
    return curve


def fit_lubrication(lub, n_modes: int, density=()) -> SpectralCurve:
    """Spectral curve with ``n_modes`` modes (and arc-length ``density`` coefficients) fitted to
    a converged LubricationResult's shape, moved along the axis so that its centroid is at
    x = 0, where the solver centres every shape (the lubrication shape starts at x = 0: as a
    seed it placed the first level's wall, whose finest panels follow the reference curve,
    beside the front half of the vesicle only)."""
    s = np.asarray(lub.s)
    keep = np.concatenate([[True], np.diff(s) > 1e-12])
    s, x, r, psi = s[keep], np.asarray(lub.x)[keep], np.asarray(lub.r)[keep], \
        np.asarray(lub.psi)[keep]
    sx, sr, sp = CubicSpline(s, x), CubicSpline(s, r), CubicSpline(s, psi)

    def curve(t):
        t = np.asarray(t, dtype=float)
        p = sp(t)
        return sx(t), np.clip(sr(t), 0.0, None), np.cos(p), -np.sin(p)

    fit = fit_curve(curve, float(s[0]), float(s[-1]), n_modes, density=density)
    return dataclasses.replace(fit, x0=fit.x0 - fit.centroid())


def spheroid_seed(nu: float, lam: float, n_modes: int) -> SpectralCurve:
    """Prolate spheroid (axis along the tube) of reduced volume ``nu`` and volume 4/3 pi lam^3."""
    def nu_of(e):                                         # e = b/a <= 1, prolate
        c = fit_curve(spheroid_curve(1.0, e), 0.0, math.pi, 32)
        return 6.0 * math.sqrt(math.pi) * c.volume() * c.area() ** -1.5
    lo, hi = 0.05, 1.0
    for _ in range(50):                                   # bisection: nu increases with e
        mid = 0.5 * (lo + hi)
        if nu_of(mid) < nu:
            lo = mid
        else:
            hi = mid
    e = 0.5 * (lo + hi)
    c = fit_curve(spheroid_curve(1.0, e), 0.0, math.pi, n_modes)
    return SpectralCurve.closed(c.modes, volume=4.0 / 3.0 * math.pi * lam**3)


def capsule_seed(nu: float, lam: float, n_modes: int) -> SpectralCurve:
    r"""Cylinder with hemispherical caps of reduced volume ``nu`` and volume 4/3 pi lam^3.

    Cap radius a and cylinder length L from :math:`V = \pi a^2 L + \tfrac43\pi a^3`,
    :math:`A = 2\pi a L + 4\pi a^2`, i.e. :math:`\tfrac23\pi a^3 - \tfrac12 A a + V = 0`, the
    cubic of the critical confinement (Chen et al. 2020 eq. lamc) with a in place of R: its
    larger root is :math:`a = \lambda/\lambda_c(\nu) < 1`, so the capsule fits in the tube
    whenever the vesicle can pass (a prolate spheroid of small nu and large lam does not).
    """
    a = lam / critical_confinement(nu)
    length = (4.0 * math.pi * (lam * nu ** (-1.0 / 3.0)) ** 2 - 4.0 * math.pi * a * a) \
        / (2.0 * math.pi * a)
    q = 0.5 * math.pi * a                                 # arc length of one cap

    def curve(t):
        t = np.asarray(t, dtype=float)
        rear, front = t < q, t > q + length
        th = np.where(rear, t / a, np.where(front, (t - q - length) / a + 0.5 * math.pi,
                                            0.5 * math.pi))
        x = np.where(rear, -a * np.cos(th), np.where(front, length - a * np.cos(th),
                                                     t - q))
        return x, a * np.sin(th), np.sin(th), np.cos(th)

    c = fit_curve(curve, 0.0, 2.0 * q + length, n_modes)
    return SpectralCurve.closed(c.modes, volume=4.0 / 3.0 * math.pi * lam**3)


# ---------------------------------------------------------------------------- one level
def _prolonged_columns(coarse: VesicleOperator, coarse_state: dict, op: VesicleOperator,
                       state: dict) -> dict:
    """Jacobian columns of ``op``'s free modes that ``coarse`` also has, from the coarse
    level's final Jacobian (``coarse_state["jacobian"]``, weighted rows at its nodes)
    interpolated in tau to ``op``'s nodes: {free index: column}; empty if the two levels
    solve for different area modes or have different arc-length densities (a mode is then
    another shape change). The unweighted rows d(u - V e_x)/dc are smooth in tau within a
    coarse panel (the velocity of a smooth shape), so the panel's Lagrange interpolant
    carries them."""
    J = coarse_state.get("jacobian")
    if (J is None or coarse.area_mode != op.area_mode
            or not np.array_equal(coarse.density, op.density)):
        return {}
    p = coarse.p
    tn, _ = gauss_legendre(p)
    bw = barycentric_weights(p)
    br = coarse.breaks
    t = op.tau.ravel()
    i = np.clip(np.searchsorted(br, t, side="right") - 1, 0, br.size - 2)
    s = 2.0 * (t - br[i]) / (br[i + 1] - br[i]) - 1.0
    d = s[:, None] - tn[None, :]
    hit = d == 0.0
    d[hit] = 1.0
    L = bw / d
    L[hit.any(axis=1)] = hit[hit.any(axis=1)]
    L /= L.sum(axis=1, keepdims=True)
    cols = i[:, None] * p + np.arange(p)
    sw_c = np.repeat(np.sqrt(coarse_state["panels"].w.ravel()), 2)
    sw_f = np.repeat(np.sqrt(state["panels"].w.ravel()), 2)
    G = J / sw_c[:, None]                                   # unweighted rows
    Gf = np.empty((sw_f.size, J.shape[1]))
    for a in (0, 1):                                        # x rows, r rows
        Gf[a::2] = np.einsum("ik,ikj->ij", L, G[a::2][cols])
    Gf *= sw_f[:, None]
    free_c = [m for m in range(coarse.disc.n_modes) if m not in coarse._dependent()]
    free_f = [m for m in range(op.disc.n_modes) if m not in op._dependent()]
    where = {m: j for j, m in enumerate(free_c)}
    return {jf: Gf[:, where[m]] for jf, m in enumerate(free_f) if m in where}


def _workers() -> int:
    """Threads for independent evaluations: numba's thread count (NUMBA_NUM_THREADS, or
    :func:`numba.set_num_threads`), so that one setting bounds both."""
    import numba  # lazy: numba

    return max(1, int(numba.get_num_threads()))


#: fixed-load points evaluated together from this many on (a difference Jacobian, not the
#: few points of a directional update) share the influence of the membrane expanded about the
#: state differentiated (:meth:`VesicleOperator.taylor`: 5 or 7 ring Stokeslets per far pair
#: and 7 per quadrature point of a near pair once, against one of each per point)
LINEARISED_POINTS = 8


def _residuals(op: VesicleOperator, modes_list, fixed=None) -> list:
    """Weighted residuals F of the shapes ``modes_list`` (None where the operator rejects one),
    evaluated ``_workers()`` at a time, each on one thread (serial assembly; the products and
    kernels release the GIL); with ``fixed`` = (g, V, panels) of a state, the residuals at
    those fixed tension coefficients and speed (:meth:`VesicleOperator.fixed_residual`), from
    LINEARISED_POINTS points on with the wall–membrane far field expanded about the state's
    panels (:meth:`VesicleOperator.linearised_finish`). Every shape starts its area secant
    from the same slope, so the result does not depend on the number of threads or on the
    order. Measured at (0.6, 1.94), 96 modes, on 2 cores: 0.08 s per evaluation against
    0.12 s one after the other."""
    slope = op._area_slope
    taylor = None
    if fixed is not None and len(modes_list) >= LINEARISED_POINTS:
        taylor = op.taylor(fixed[2])

    def one(modes, serial=True):
        with serial_assembly() if serial else nullcontext(), single_threaded_blas():
            try:
                curve = op.curve(modes, slope=slope)
                if taylor is not None:
                    return op.linearised_residual(curve, fixed[0], fixed[1], taylor)
                if fixed is not None:
                    return op.fixed_residual(curve, *fixed[:2])
                return op.evaluate(curve)["F"]
            except InvalidParameterError:
                return None

    workers = min(_workers(), len(modes_list))
    if workers <= 1:
        out = [one(m, serial=False) for m in modes_list]
    else:
        pool = ThreadPoolExecutor(workers)
        try:
            out = list(pool.map(one, modes_list))
        finally:                   # on Ctrl-C: drop the queued shapes, finish the running ones
            pool.shutdown(wait=True, cancel_futures=True)
    return out if taylor is None else op.linearised_finish(taylor, out)


def level_function(op: VesicleOperator, template):
    """The residual of one level as :mod:`bem.newton` takes it: ``fun(z)`` = (F, state) of
    the shape with free modes z (the other modes from ``template``), with ``fun.many``
    (independent points evaluated concurrently, :func:`_residuals`) and ``fun.fixed``
    (Jacobian points at the tension and V of the state differentiated, projected off their
    columns: Kaufman's variable-projection Jacobian, :meth:`VesicleOperator.fixed_residual`)."""
    def fun(z):
        st = op.evaluate(op.curve(op.full(z, template)))
        return st["F"], st

    def many(points, at=None):
        return _residuals(op, [op.full(z, template) for z in points], at)

    def fixed(state):
        at = (state["g"], state["V"], state["panels"])
        return (lambda points: many(points, at)), _range_projector(state["M"])

    fun.many, fun.fixed = many, fixed
    return fun


def _solve_level(nu, lam, ca_b, disc, seed: SpectralCurve, n_tension, *, xtol, max_iter,
                 seed_level=False, valley=False, carrier=False, deadline=None, coarse=None):
    """Levenberg–Marquardt at one resolution from ``seed``
    (:func:`bem.newton.valley_levenberg_marquardt` if ``valley``, with 8 ``max_iter`` cheap
    iterations, else :func:`bem.newton.levenberg_marquardt`); returns (state, op, info), the
    state with the final Jacobian. ``seed_level``: the first level of a ladder (a smaller
    Jacobian budget); ``carrier``: a valley level that only seeds the next one (one difference
    Jacobian). ``coarse``: (op, state) of the level below (plain method only): its Jacobian,
    interpolated to this level's nodes, gives the columns of the modes it has, and only the
    new modes are differenced (:func:`_prolonged_columns`)."""
    ref = fit_curve(seed.sample, 0.0, 1.0, disc.n_modes, density=seed.density) \
        if seed.n_modes != disc.n_modes else seed
    op = VesicleOperator(nu, lam, ca_b, disc, ref, n_tension)
    template = op.curve(ref.modes).modes.copy()
    fun = level_function(op, template)
    z0, start, J0, extra = op.free(template), None, None, 0
    if coarse is not None and not (deadline is not None and deadline.expired()):
        try:
            start, extra = fun(z0), 1
        except InvalidParameterError:                # reported by the Levenberg–Marquardt
            start = None
        known = _prolonged_columns(*coarse, op, start[1]) if start else {}
        if known:
            J0, n = difference_jacobian(fun, z0, start[0], 1e-7, known, start[1])
            extra += n
    if valley:
        rep = valley_levenberg_marquardt(fun, z0, tol=xtol, max_iter=8 * max_iter,
                                         deadline=deadline, start=start, jacobian=J0,
                                         max_jacobians=1 if carrier else 2 if seed_level else 4)
    else:
        rep = levenberg_marquardt(fun, z0, tol=xtol, max_iter=max_iter,
                                  max_jacobians=3 if seed_level else 8, deadline=deadline,
                                  stall=0.9 if seed_level else None, floor_ratio=0.99,
                                  start=start, jacobian=J0)
    rep.evaluations += extra
    if rep.payload is None:
        raise InvalidParameterError("initial", "a shape rejected by the operator", rep.message)
    state = rep.payload
    state["jacobian"] = rep.jacobian
    info = {"success": rep.success, "message": rep.message, "iterations": rep.iterations,
            "evaluations": rep.evaluations, "jacobians": rep.jacobians,
            "norm0": rep.history[0], "norm": rep.history[-1], "area_mode": op.area_mode}
    return state, op, info


#: arc-length densities of the shape parametrisation: curve -> density coefficients
_DENSITIES = {
    "curvature": equidistributing_density,
    "bend": lambda curve, n: equidistributing_density(curve, n, gradient=1.0),
    "film": film_density,
}

#: estimated length L/R above which :func:`solve_vesicle` uses the "bend" density by
#: default: long vesicles (ν ≲ 0.75 near λc) need it, e.g. at (0.7, 1.5) the residual falls
#: ÷4.5 per +8 modes with it against ÷2 with uniform arc length, while short ones converge
#: faster without it ((0.9, 1.0): 32-mode residual 2.3e-5 uniform, 1.0e-4 "bend")
LONG_VESICLE = 5.0

#: lam/lam_c from which :func:`solve_vesicle` uses the film density and continuation by default
NEAR_CRITICAL = 0.9

#: estimated length ℓ ≈ ℓc λ/λc [R] above which a vesicle near lam_c is not reached by
#: continuation rungs but from the lubrication shape at its own λ through carrier levels:
#: measured, (0.7, 0.95 λc), ℓ = 7.3, needs the rungs (from its own lubrication shape it ends
#: in a spurious minimum, residual 2e-2), while (0.6, 0.98 λc), ℓ = 10.8, is led astray by
#: 32-mode rungs (residual 1e-2 at each rung; at the target Δp⁺ 2818 at 40 modes, against
#: 1778 mode-converged) and converges from its own lubrication shape
RUNG_MAX_LENGTH = 9.0

#: levels in a row whose density is re-built on the BEM shape of the level before, for a long
#: vesicle near lam_c started from its own lubrication shape (ℓ > RUNG_MAX_LENGTH): the first
#: re-built density comes from a level on the lubrication shape's density, which misses the
#: BEM shape's rear film neck, and resolves it only in part. Measured at (0.6, 0.98 lam_c),
#: Ca_B = 50 (consistent levels from 56 / 64 modes; V/U, γ_max, residual at 64 / 88 modes):
#: one re-build 1.021926 / 1.020839, 930.6 / 1005.7, 3.1e-3 / 5.6e-4, contraction ~0.4 per +8
#: modes, not converged at 88 modes (1602 BIE solves); two re-builds 1.021342 / 1.020790,
#: 964.9 / 1009.8, 1.8e-3 / 2.1e-4, contraction 0.26-0.35, converged at 88 modes (1587 BIE
#: solves; mode-converged 1.020781, 1011). The unconverged carrier levels make the shape the
#: density is built on depend on details such as the wall mesh: with WALL_BODY_LENGTH 6 R
#: instead of 5 R the same ladder contracts by ~0.38 and converges at 96 modes (1745 BIE
#: solves), which is why this regime keeps five consistent levels (``max_modes``). Farther from
#: lam_c one re-build is enough: at the red blood cell (0.61, 0.71 lam_c) a second one costs a
#: level (682 BIE solves, 64 modes, against 454 and 56)
NEAR_CRITICAL_REBUILDS = 2

#: level (index in the ladder 16, 24, ...) on whose BEM shape the density is re-built for the
#: rest of a short vesicle's automatic ladder (the seed's density family; "bend" for uniform)
REBUILD_LEVEL = 0


def _rungs(ratio: float) -> list[float]:
    """Continuation rungs below ``ratio``: 1 - lam/lam_c = 0.1, 0.05, 0.025, ..."""
    out, gap = [], 1.0 - NEAR_CRITICAL
    while 1.0 - gap < ratio - 1e-9:
        out.append(round(1.0 - gap, 12))
        gap *= 0.5
    return out


# ---------------------------------------------------------------------------- outputs
def _cross(u, v):
    """z-component of the cross product of 2-vectors (last axis)."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _self_intersects(x, r) -> bool:
    """Whether the polyline (x, r) crosses itself or the axis inside (O(n^2), n ~ 400)."""
    if np.any(r[1:-1] <= 0.0):
        return True
    p = np.column_stack([x, r])
    a, b = p[:-1], p[1:]
    n = len(a)
    for i in range(n - 2):
        c, d = a[i + 2:], b[i + 2:]
        if i == 0:
            c, d = c[:-1], d[:-1]                         # first and last share the axis
        d1 = _cross(b[i] - a[i], c - a[i])
        d2 = _cross(b[i] - a[i], d - a[i])
        d3 = _cross(d - c, a[i] - c)
        d4 = _cross(d - c, b[i] - c)
        if np.any((d1 * d2 < 0) & (d3 * d4 < 0)):
            return True
    return False


def _outputs(nu, lam, op: VesicleOperator, st: dict) -> dict:
    curve, p = st["curve"], st["panels"]
    rb, wb = p.r.ravel(), p.w.ravel()
    vol = float(math.pi * np.sum(rb**2 * p.tx.ravel() * wb))
    area = float(2.0 * math.pi * np.sum(rb * wb))
    xr, xf = curve.extent()
    return {"V_over_U": st["V"], "dp_plus_R": st["dp"], "dp_plus_R0": st["dp"] * lam,
            "ell": xf - _rearmost(curve), "ell_poles": xf - xr,
            "film_min": 1.0 - curve.max_radius(), "residual": st["residual"],
            "volume_error": abs(vol / op.volume - 1.0), "area_error": abs(area / op.area - 1.0),
            "tension_max": _tension_max(curve, st["g"]),
            "panels": op.panel_counts | {"tension": op.n_tension}}


def _refined_extremum(f, n: int = 401) -> tuple[float, float]:
    """(tau, f) of the largest value of the smooth function ``f`` on [0, 1]: the best of ``n``
    equally spaced samples, refined by a bounded scalar search between its neighbours (a
    sampled maximum differs between parametrisations by its sampling error, 1e-5 relative for
    γ_max at 401 samples, which the refinement pair would read as discretisation error)."""
    t = np.linspace(0.0, 1.0, n)
    v = f(t)
    i = int(np.argmax(v))
    lo, hi = t[max(i - 1, 0)], t[min(i + 1, n - 1)]
    res = minimize_scalar(lambda x: -float(f(np.array([x]))[0]), bounds=(lo, hi),
                          method="bounded", options={"xatol": 1e-12})
    return (float(res.x), -float(res.fun)) if -res.fun > v[i] else (float(t[i]), float(v[i]))


def _tension_max(curve: SpectralCurve, g) -> float:
    """Largest membrane tension [ηU] (:func:`_refined_extremum`)."""
    return _refined_extremum(lambda t: tension_profile(curve, g, t)[0])[1]


def _rearmost(curve: SpectralCurve) -> float:
    """Axial position of the rearmost point of the membrane [R]: the rear pole of a bullet, the
    rim of a parachute (:func:`_refined_extremum` of -x)."""
    return -_refined_extremum(lambda t: -curve.position(t)[0])[1]


_KEYS = ("V_over_U", "dp_plus_R0", "tension_max")

#: safety factor of the extrapolated error estimate (:func:`_error_estimate`): the observed
#: contraction ratio of the successive differences varies by up to 2.4x from one level to the
#: next in the pre-asymptotic range (γ_max at (0.6, 1.94): 0.14 then 0.33, docs/validation.md)
ESTIMATE_SAFETY = 3.0
#: smallest contraction ratio the estimate uses: the first difference of a ladder is often
#: pre-asymptotic and inflates d1 (Δp⁺ at (0.8, 1.0): observed 0.019 from 24-32-40 modes,
#: then 0.08 from 32-40-48; with the observed ratio the 40-mode error 1.9e-6 is estimated
#: as 1.4e-6, with this floor as 8e-6)
MIN_CONTRACTION = 0.1


def _error_estimate(outs: list[dict]) -> dict:
    r"""Estimated discretisation error of the last of ``outs`` (the outputs of successive
    levels of one consistent ladder: same density, +8 modes each) for the keys of ``_KEYS``.

    The spectral shape converges geometrically, :math:`q_N - q_\infty \propto \rho^{N/8}`
    (observed at (0.9, 1.0), (0.7, 1.5) and (0.6, 1.94), docs/validation.md); with the last
    two differences :math:`d_1, d_2` of an output and the contraction ρ < 1 the error of the
    last level is :math:`d_2\,\rho/(1-\rho)` (the tail of the geometric series), here
    multiplied by ``ESTIMATE_SAFETY``, with ρ at least ``MIN_CONTRACTION``. The rate is the
    discretisation's (set by the shape's analyticity, not by the output), so ρ is the median
    of the outputs' ratios :math:`d_2/d_1`: one output whose error has parts of opposite sign
    does not contract cleanly (Δp⁺ at (0.6, 1.94), 72 → 96 modes: differences +0.043,
    +0.056, +0.037 while V/U and γ_max contract by 0.29–0.37 per level; on its own ratio 0.66
    its 96-mode estimate was 0.21, 30 times the true error, and the solve ended "not
    converged"). An output whose own differences do not contract is estimated at least at
    its last difference. With two levels only, or where the median ratio is not below 1, the
    estimate is :math:`d_1 + d_2` (:math:`d_2` for a pair): the raw difference, an
    overestimate by :math:`(1-\rho)/\rho` for a contracting sequence. NaN for one level.
    """
    diffs = {}
    for k in _KEYS:
        q = [o[k] for o in outs]
        diffs[k] = (abs(q[-2] - q[-3]) if len(q) >= 3 else math.nan,
                    abs(q[-1] - q[-2]) if len(q) >= 2 else math.nan)
    ratios = [d2 / d1 for d1, d2 in diffs.values() if d1 > 0.0]
    rho = float(np.median(ratios)) if ratios else math.nan
    out = {}
    for k, (d1, d2) in diffs.items():
        if rho < 1.0:
            r = max(rho, MIN_CONTRACTION)
            tail = ESTIMATE_SAFETY * d2 * r / (1.0 - r)
            out[k] = tail if d2 < d1 else max(tail, d2)
        else:
            out[k] = d2 + (d1 if d1 == d1 else 0.0)
    return out


def _tolerance(key: str, tol: float, tension_tol: float) -> float:
    return tension_tol if key == "tension_max" else tol


def _within(err: dict, out: dict, tol: float, tension_tol: float) -> bool:
    """Whether every estimated error is within its relative tolerance."""
    return all(err[k] <= _tolerance(k, tol, tension_tol) * abs(out[k]) for k in _KEYS)


def check_vesicle_case(nu, lam, lam_ratio, ca_b):
    nu, lam, lam_c = resolve_confinement(
        nu, lam, lam_ratio, nu_reason="a vesicle with excess area (nu < 1) is needed")
    ca_b = float(check_positive("ca_b", ca_b, reason="Ca_B = eta U R0^2/kappa"))
    if not CA_B_MIN <= ca_b <= CA_B_MAX:
        raise InvalidParameterError(
            "ca_b", ca_b, f"{CA_B_MIN:g} <= ca_b <= {CA_B_MAX:g}",
            "Ca_B = eta U R0^2/kappa; outside it the membrane is rigid, or bending negligible, "
            "to within the solver's accuracy (red blood cells: Ca_B ~ 1-1000)")
    return nu, lam, lam_c, ca_b


def mode_count(name, value) -> int:
    """An integer number of shape modes, 8 <= value <= MAX_MODES (the vesicle's envelope)."""
    return _drop_mode_count(name, value, 8, MAX_MODES)


def check_vesicle_inputs(nu, lam=None, *, lam_ratio=None, ca_b=50.0, n_modes=None,
                         tol=1e-4, tension_tol=1e-2, residual_tol=1e-3, max_modes=None,
                         rung_modes=32,
                         density_terms=16, max_iter=40, max_time=None):
    """Check the inputs of :func:`solve_vesicle` (ranges and the resource envelope of the module
    docstring) without any BEM work. Returns (nu, lam, lam_c, ca_b, n_modes, tol,
    residual_tol, max_modes, rung_modes, density_terms, max_iter) as Python numbers
    (``max_modes`` None stays None: chosen from the vesicle's length). Raises
    :class:`InvalidParameterError` (or CannotPassError for lam >= lam_c) naming the input."""
    nu, lam, lam_c, ca_b = check_vesicle_case(nu, lam, lam_ratio, ca_b)
    tol = float(check_range("tol", tol, 1e-12, 0.5))
    tension_tol = float(check_range("tension_tol", tension_tol, 1e-12, 0.5))
    residual_tol = float(check_range("residual_tol", residual_tol, 1e-14, 10.0))
    if max_modes is not None:
        max_modes = mode_count("max_modes", max_modes)
    if n_modes is not None:
        n_modes = mode_count("n_modes", n_modes)
    elif max_modes is not None and max_modes < 24:
        raise InvalidParameterError("max_modes", max_modes, f"24 <= max_modes <= {MAX_MODES}",
                                    "the automatic refinement solves 16, 24, ... modes and "
                                    "needs a pair; for a single coarse solve give n_modes")
    rung_modes = mode_count("rung_modes", rung_modes)
    density_terms = int(check_range("density_terms", density_terms, 1, 64))
    max_iter = int(check_range("max_iter", max_iter, 1, 1000))
    if max_time is not None:
        Deadline(max_time)                               # 0 < max_time < inf
    return (nu, lam, lam_c, ca_b, n_modes, tol, tension_tol, residual_tol, max_modes,
            rung_modes, density_terms, max_iter)


def _solve_from(nu: float, lam: float | None = None, *, lam_ratio: float | None = None,
                ca_b: float = 50.0, initial=None, n_modes: int | None = None,
                tol: float = 1e-4, tension_tol: float = 1e-2, residual_tol: float = 1e-3,
                max_modes: int | None = None,
                order: int = DEFAULT_ORDER, xtol: float = 1e-9, max_iter: int = 40,
                density: str = "auto", density_terms: int = 16,
                continuation: bool | None = None, rung_modes: int = 32,
                valley: bool | None = None, max_time: float | None = None):
    r"""Steady vesicle from one start: ``initial``, or with None the solver's own seed
    (lubrication shape, continuation near lam_c), refined by the mode ladder with its error
    estimate. Parameters and result as :func:`solve_vesicle`, whose pipeline calls this once
    per start."""
    t_start = time.perf_counter()
    (nu, lam, lam_c, ca_b, n_modes, tol, tension_tol, residual_tol, max_modes, rung_modes,
     density_terms, max_iter) = check_vesicle_inputs(
        nu, lam, lam_ratio=lam_ratio, ca_b=ca_b, n_modes=n_modes, tol=tol,
        tension_tol=tension_tol, residual_tol=residual_tol, max_modes=max_modes,
        rung_modes=rung_modes, density_terms=density_terms, max_iter=max_iter,
        max_time=max_time)
    deadline = Deadline(max_time)
    clock = time.monotonic()
    max_modes_given, density_given, valley_given = max_modes, density, valley
    if density not in ("auto", "uniform", *_DENSITIES):
        raise InvalidParameterError("density", density,
                                    '"auto", "uniform", "curvature", "bend" or "film"')
    ratio = lam / lam_c
    ell = critical_length(nu) * ratio                # estimated length L/R (Chen eq. sL)
    long = ell > LONG_VESICLE
    if continuation is None:
        continuation = initial is None and ratio > NEAR_CRITICAL and ell <= RUNG_MAX_LENGTH
    if valley is None:
        valley = long
    if density == "auto":
        density = "film" if ratio >= NEAR_CRITICAL and not long else "bend"
    # the ladder (module docstring): levels of ``sequence``; a seed that is not a BEM minimum
    # has the density re-built on the BEM shape of level ``rebuild`` (an index; near lam_c
    # again on the next level's, ``rebuilds``), and every later level keeps it (a consistent
    # ladder); a BEM seed (``initial`` a result, or the continuation rungs) already gives the
    # density its shape
    bem_seed = continuation or isinstance(initial, (VesicleResult, SpectralCurve))
    rebuilt = density if density in _DENSITIES else "bend"
    first = max(24, 8 * round(0.75 * ell) - 16) if long else 16
    # levels whose density is re-built on the shape of the level before (NEAR_CRITICAL_REBUILDS)
    rebuilds = (NEAR_CRITICAL_REBUILDS if valley and ratio > NEAR_CRITICAL and not bem_seed
                and n_modes is None else 1)
    if max_modes is None:      # a second re-build takes a level: the consistent ladder keeps 5
        max_modes = min(MAX_MODES, first + 32 + 8 * rebuilds if long else 80)
    if n_modes is not None:
        sequence, rebuild = [max(6, round(2 * n_modes / 3)), n_modes], None
    elif bem_seed:       # from the seed's mode count near lam_c (a refit to fewer modes
        # loses the thin film: from a 0.95 lam_c result refitted to 16 modes, the film of
        # (0.98, 0.98 lam_c) closed); below, a continued result restarts low
        start = (rung_modes if continuation else initial.modes.size if ratio > NEAR_CRITICAL
                 else min(initial.modes.size, first))
        start = min(max(16, 8 * round(start / 8)), max_modes - 16)
        sequence, rebuild = list(range(start, max_modes + 1, 8)), None
    elif valley:                     # carriers every 16 modes below the re-built density
        first = min(first, max_modes - 16)
        sequence = list(range(16, first, 16)) + list(range(first, max_modes + 1, 8))
        rebuild = sequence.index(first)
    else:
        sequence, rebuild = list(range(16, max_modes + 1, 8)), REBUILD_LEVEL
    seed_source = "initial"
    rung_log = {}

    def timed_out(what: str):
        return VesicleResult(nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=Status.TIME_LIMIT,
                             tol=tol, residual_tol=residual_tol, iterations=dict(rung_log),
                             timings={"total_s": time.perf_counter() - t_start},
                             message=f"{deadline.message()} ({what})")
    if continuation:
        rung_kw = {"ca_b": ca_b, "n_modes": rung_modes,
                   "tol": 0.5, "tension_tol": 0.5, "residual_tol": 10.0, "order": order,
                   "density": density,
                   "density_terms": density_terms, "continuation": False}
        rung = None
        for q in _rungs(ratio):
            left = None if max_time is None else max_time - (time.monotonic() - clock)
            if left is not None and left <= 0.0:
                return timed_out(f"continuation rung lam/lam_c = {q:g}")
            rung = _solve_from(nu, lam_ratio=q, initial=rung, max_time=left, **rung_kw)
            if deadline.expired():
                return timed_out(f"continuation rung lam/lam_c = {q:g}")
            rung_log[f"rung{q:g}"] = {
                "evaluations": sum(v["evaluations"] for v in rung.iterations.values()),
                "seconds": rung.timings.get("total_s", math.nan), "residual": rung.residual}
            if rung.modes.size == 0 or rung.status is Status.NO_STEADY_STATE:
                return VesicleResult(
                    nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=rung.status, tol=tol,
                    residual_tol=residual_tol, timings={"total_s": time.perf_counter() - t_start},
                    message=f"continuation failed at lam/lam_c = {q:g}: {rung.message}")
            log.info("solve_vesicle continuation rung lam/lam_c=%g: V/U=%.6f dp+R0=%.5g "
                     "residual %.1e", q, rung.V_over_U, rung.dp_plus_R0, rung.residual)
        if rung is not None:
            initial = rung
            seed_source = f"continuation (lam/lam_c = {', '.join(f'{r:g}' for r in _rungs(ratio))})"
    from_lubrication = False                         # the seed is already fitted with density
    if deadline.expired():
        return timed_out("before the seed")
    if isinstance(initial, SpectralCurve):
        seed = initial
    elif isinstance(initial, LubricationResult) or initial is None:
        seed = None
        if initial is None:
            seed, _ = lubrication_seed(nu, lam, ca_b, sequence[0], density, density_terms,
                                       max_time=deadline.remaining())
            seed_source = "lubrication"
        elif initial.success:
            seed = seed_from_lubrication(initial, sequence[0], density, density_terms)
        from_lubrication = seed is not None
        if seed is None:
            seed = spheroid_seed(nu, lam, sequence[0])
            seed_source = "spheroid"
            if seed.max_radius() > 0.95:                   # a spheroid of small nu: too fat
                seed = capsule_seed(nu, lam, sequence[0])
                seed_source = "capsule"
    elif isinstance(initial, VesicleResult):
        if initial.modes.size == 0:
            raise InvalidParameterError("initial", "a VesicleResult without a shape",
                                        "a result with a shape")
        seed = initial.curve()
    else:
        raise InvalidParameterError("initial", type(initial).__name__,
                                    "a VesicleResult, SpectralCurve, LubricationResult or None")
    if density != "uniform" and not from_lubrication:
        seed = fit_curve(seed.sample, 0.0, 1.0, sequence[0],
                         density=_DENSITIES[density](seed, density_terms))
    levels, timings, iterations = [], {}, dict(rung_log)
    status, message = Status.CONVERGED, ""        # the ladder's own failure, if any
    prev = seed
    consistent = 0           # index of the first level on the density of the last one
    for i, n in enumerate(sequence):
        if deadline.expired():
            status = Status.TIME_LIMIT
            message = f"{deadline.message()} (before the level with {n} modes)"
            break
        disc = vesicle_discretisation(n, order)
        t0 = time.perf_counter()
        # the seeds of this level in the order tried: after one whose density the level
        # rejects, a density re-built on a shape that does not carry it (at (0.95, 0.2 lam_c)
        # the 16-mode level stopped at a 5e-2 step and the 24-mode curve on its density had no
        # positive volume) gives way to the seed's density, and a first level whose seed
        # density fails (the "bend" density of the lubrication shape at (0.85, 0.2 lam_c): a
        # curve c_1 cannot close) starts on uniform arc length (None: made when needed)
        seeds = [prev, None] if not levels and np.size(prev.density) else [prev]
        if rebuild is not None and rebuild < i <= rebuild + rebuilds and levels:
            # the density re-built on the BEM shape of the level before (it resolves what the
            # seed's density misses, e.g. a long vesicle's rear film neck)
            try:
                seeds = [fit_curve(prev.sample, 0.0, 1.0, n,
                                   density=_DENSITIES[rebuilt](prev, density_terms)), prev]
                consistent = len(levels)
            except InvalidParameterError:
                pass
        # a carrier starts from a fresh difference Jacobian: one prolonged from the (unfinished)
        # level below led the cold start of (0.6, 1.94) to Δp⁺ 2829 at 32 modes (1778 converged)
        carrier = rebuild is not None and valley and i < rebuild
        st = rejected = None
        for k, seed in enumerate(seeds):
            if k:
                log.info("solve_vesicle: density rejected at %d modes (%s)", n, rejected)
                consistent = 0
            as_carrier = carrier and not k
            try:
                st, op, info = _solve_level(
                    nu, lam, ca_b, disc, fit_curve(prev.sample, 0.0, 1.0, n) if seed is None
                    else seed, n, xtol=xtol, max_iter=max_iter, seed_level=not levels,
                    valley=valley, carrier=as_carrier, deadline=deadline,
                    coarse=(levels[-1][1], levels[-1][0]) if levels and not as_carrier else None)
                break
            except InvalidParameterError as exc:
                rejected = exc
        if st is None:
            # no seed of this level could start: the solve's start if it is the first level
            status = Status.NOT_CONVERGED if levels else Status.REJECTED_START
            message = f"level with {n} modes: {rejected}"
            break
        timings[f"modes{n}_s"] = time.perf_counter() - t0
        iterations[f"modes{n}"] = info
        out = _outputs(nu, lam, op, st)
        levels.append((st, op, out))
        log.info("solve_vesicle nu=%g lam=%g modes=%d: V/U=%.10f dp+R0=%.8g gmax=%.6g "
                 "residual %.2e (%s)", nu, lam, n, out["V_over_U"], out["dp_plus_R0"],
                 out["tension_max"], out["residual"], info["message"])
        if not info["success"]:
            if deadline.expired():
                status = Status.TIME_LIMIT
                message = f"{deadline.message()} (in the level with {n} modes)"
                break
            if n == sequence[-1]:
                status = Status.NOT_CONVERGED
                message = f"Levenberg–Marquardt failed with {n} modes: {info['message']}"
                break
            # a coarser level only seeds the next one, which is judged on its own (residual,
            # refinement pair): an unfinished coarse level is not a failure of the solve
            log.info("solve_vesicle: level with %d modes unfinished (%s); refining", n,
                     info["message"])
        prev = st["curve"]
        err = _error_estimate([lv[2] for lv in levels[consistent:]])
        if (len(levels) - consistent >= (2 if n_modes is not None else 3)
                and _within(err, levels[-1][2], tol, tension_tol)
                and levels[-1][2]["residual"] <= residual_tol):
            break
    timings["total_s"] = time.perf_counter() - t_start
    if not levels and bem_seed and not continuation and not deadline.expired():
        # a continued shape that cannot start at this lam (its volume re-imposed, the film of
        # (0.98, 0.95 lam_c) closed at 0.98 lam_c): the solver's own seed and continuation
        log.info("solve_vesicle: the given initial shape was rejected (%s); own seed", message)
        left = None if max_time is None else max_time - (time.monotonic() - clock)
        if left is None or left > 0.0:
            return _solve_from(
                nu, lam, ca_b=ca_b, n_modes=n_modes, tol=tol, tension_tol=tension_tol,
                residual_tol=residual_tol, max_modes=max_modes_given, order=order, xtol=xtol,
                max_iter=max_iter, density=density_given, density_terms=density_terms,
                rung_modes=rung_modes, valley=valley_given, max_time=left)
    if not levels:
        return VesicleResult(nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=status,
                             message=message, tol=tol, residual_tol=residual_tol,
                             iterations=iterations, timings=timings)
    st, op, fine = levels[-1]
    err = _error_estimate([lv[2] for lv in levels[consistent:]])
    curve = st["curve"]
    prof = _profile(curve, st["g"])
    # every problem is named; the status is the leading one (lubrication.results.PRECEDENCE)
    problems, found = ([message], [status]) if message else ([], [])
    if _self_intersects(prof["x"], prof["r"]):
        problems.append("the membrane self-intersects")
        found.append(Status.NO_STEADY_STATE)
    if fine["film_min"] < 1e-3:
        problems.append(f"the film closes (min gap {fine['film_min']:.2e} R)")
        found.append(Status.NO_STEADY_STATE)
    bad = [k for k in _KEYS if not err[k] <= _tolerance(k, tol, tension_tol) * abs(fine[k])]
    if bad:
        problems.append("estimated discretisation error above the tolerance in "
                        + ", ".join(f"{k} ({err[k] / abs(fine[k]):.1e} > "
                                    f"{_tolerance(k, tol, tension_tol):g})" for k in bad))
        found.append(Status.UNRESOLVED)
    if not fine["residual"] <= residual_tol:
        problems.append(f"steady residual max|u - V e_x| = {fine['residual']:.2e} exceeds "
                        f"residual_tol={residual_tol:g}")
        found.append(Status.NOT_CONVERGED)
    status = leading_status(found)
    success = status is Status.CONVERGED
    message = ("; ".join(problems) if problems else
               f"converged: {fine['panels']['modes']} modes, estimated errors "
               + ", ".join(f"{k} {err[k]:.1e}" for k in _KEYS)
               + f", residual {fine['residual']:.1e}")
    if not success:              # one start of the pipeline: solve_vesicle reports the outcome
        log.info("solve_vesicle start (nu=%g, lam=%g): %s", nu, lam, message)
    try:
        wall_x, wall_shear = op.wall_shear(curve, st["g"])
        wall_x = wall_x - curve.position(np.array([0.0]))[0][0]    # from the rear pole
    except InvalidParameterError:                     # a shape touching the wall
        wall_x = wall_shear = np.empty(0)
    k_rear = curve.curvatures(np.array([0.0]))[0][0]
    k_front = curve.curvatures(np.array([1.0]))[0][0]
    parachute = bool(k_rear < 0.0 or np.min(prof["x"]) < prof["x"][0] - 1e-12)
    history = [(lv[2]["panels"]["modes"], lv[2]["residual"], lv[2]["V_over_U"],
                lv[2]["dp_plus_R0"], lv[2]["tension_max"]) for lv in levels]
    return VesicleResult(
        nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=status, message=message,
        V_over_U=fine["V_over_U"], dp_plus_R0=fine["dp_plus_R0"], dp_plus_R=fine["dp_plus_R"],
        ell=fine["ell"], ell_poles=fine["ell_poles"], film_min=fine["film_min"],
        tension_max=fine["tension_max"],
        wall_shear_max=float(np.max(wall_shear)) if wall_shear.size else math.nan,
        wall_x=wall_x, wall_shear=wall_shear,
        tension_rear=float(prof["tension"][0]), tension_front=float(prof["tension"][-1]),
        curvature_rear=-float(k_rear), curvature_front=-float(k_front),
        shape_class="parachute" if parachute else "bullet", error_estimate=err,
        volume_error=fine["volume_error"], area_error=fine["area_error"],
        residual=fine["residual"], tol=tol, residual_tol=residual_tol, panels=fine["panels"],
        refinement=history, seed=seed_source, iterations=iterations, timings=timings,
        modes=curve.modes.copy(), density=np.asarray(curve.density).copy(),
        tension_modes=np.asarray(st["g"]).copy(), **prof)


#: Reach of the seed bank: stored shapes farther than this (module distance of
#: :mod:`bem.seed_bank`, about one build grid step per unit) are not tried as starts.
BANK_REACH = 3.0
#: Stored shapes tried as starts, nearest first.
BANK_STARTS = 2
#: A stored shape of the other shape class within this distance is tried once the solve has
#: converged: where it converges to that class too, the point is bistable.
BRANCH_REACH = 1.5


def _starts(nu: float, lam: float, ratio: float, ca_b: float, branch: str | None,
            seed_bank: bool) -> list:
    """The starts of :func:`solve_vesicle` in the order tried: (label, make the initial shape)
    pairs, None the solver's own seed."""
    own = [("own", lambda: None)]
    if not seed_bank:
        return own
    bank = [(seed.label(), lambda seed=seed: seed.curve(lam))
            for seed in load_seed_bank().nearest(nu, ratio, ca_b, k=BANK_STARTS,
                                                 shape_class=branch, within=BANK_REACH)]
    return own + bank if ratio > NEAR_CRITICAL else bank + own


def _other_branch(nu, lam, ratio, ca_b, res: VesicleResult, solve) -> dict:
    """The steady state of the other shape class at this point, if a stored shape of that
    class within BRANCH_REACH converges to it: its class and outputs, else {}."""
    other = "bullet" if res.shape_class == "parachute" else "parachute"
    near = load_seed_bank().nearest(nu, ratio, ca_b, shape_class=other, within=BRANCH_REACH)
    if not near:
        return {}
    try:
        alt = solve(near[0].curve(lam))
    except InvalidParameterError:
        return {}
    if not (alt.success and alt.shape_class == other):
        return {}
    return {"shape_class": other, "seed": near[0].label(),
            **{k: getattr(alt, k) for k in ("V_over_U", "dp_plus_R0", "ell", "film_min")}}


@single_threaded_blas()      # small dense products between numba loops (bem.threads)
def solve_vesicle(nu: float, lam: float | None = None, *, lam_ratio: float | None = None,
                  ca_b: float = 50.0, initial=None, branch: str | None = None,
                  seed_bank: bool = True, n_modes: int | None = None,
                  tol: float = 1e-4, tension_tol: float = 1e-2, residual_tol: float = 1e-3,
                  max_modes: int | None = None,
                  order: int = DEFAULT_ORDER, xtol: float = 1e-9, max_iter: int = 40,
                  density: str = "auto", density_terms: int = 16,
                  continuation: bool | None = None, rung_modes: int = 32,
                  valley: bool | None = None, max_time: float | None = None):
    r"""Steady vesicle (inextensible bending membrane, viscosity ratio 1) on the tube axis.

    The pipeline (docs/vesicle-solver.md): without ``initial``, the starts are the nearest
    converged shapes of the seed bank (:mod:`bem.seed_bank`, ``BANK_STARTS`` within
    ``BANK_REACH``) and the solver's own seed (the lubrication shape, continuation in λ/λc near
    lam_c), the bank first below ``NEAR_CRITICAL`` and last above it; each start is refined by
    the mode ladder with its error estimate, and the first that converges is returned. A
    converged point is then probed for a second steady state: the nearest stored shape of the
    other shape class within ``BRANCH_REACH``, solved in turn; where it converges to that class
    the point is bistable, and the result says so (``other_branch``, the message).

    Parameters
    ----------
    nu : float
        Reduced volume, 0 < nu < 1 [-].
    lam, lam_ratio : float
        Confinement R0/R, or lam/lam_c; exactly one, 0 < lam < lam_c(nu) [-].
    ca_b : float
        Bending capillary number ηUR0²/κ (Chen et al. 2020 use 50), CA_B_MIN = 1e-3 <= ca_b
        <= CA_B_MAX = 1e6 [-].
    initial : VesicleResult, SpectralCurve or LubricationResult, optional
        Initial shape, the only start tried. Default: the pipeline's starts (above); the
        solver's own seed among them is the lubrication solution at the same parameters, else
        a prolate spheroid of the right nu.
    n_modes : int, optional
        Shape modes of the fine level of a single refinement pair (round(2n/3), n), both on
        the seed's density; its error estimate is the pair difference. Default: the automatic
        ladder (module docstring, "Ladder and error estimate"): levels 16, 24, ... up to
        ``max_modes``, the density re-built once on a BEM minimum, stopped when three levels
        on that density give an estimated error within ``tol`` (V/U, Δp⁺) and ``tension_tol``
        (γ_max) and the residual is below ``residual_tol``. Default ``max_modes``: 80, or for
        a long vesicle 40 more than the level whose shape re-builds the density (about 6
        modes per tube radius of its estimated length ℓ ≈ ℓc λ/λc, Chen et al. 2020 eq. sL,
        minus 16), 48 more near lam_c where the density is re-built twice (96 at
        (0.6, 0.98 λc)); at most MAX_MODES.
    tol, tension_tol : float
        Relative tolerances of the estimated discretisation error of V/U and Δp⁺, and of
        γ_max (a peak value of the tension, which converges more slowly: at (0.6, 1.94) its
        72-mode error is 4e-3 while V/U's is 3e-5).
    residual_tol : float
        Tolerance of the steady residual max|u − V e_x| of the fine level [U]. The default
        1e-3 is a test of steadiness, not of accuracy (the error estimate is): the genuine
        steady states measured have 1e-7–8e-4 at their converged level, the spurious
        least-squares minima 1.2e-2–2.1e-2 at every mode count.
    order : int
        Gauss nodes per panel.
    xtol, max_iter : float, int
        Relative step tolerance and iteration budget of each Levenberg–Marquardt level
        (:func:`bem.newton.levenberg_marquardt`; it also stops at the residual floor).
    density : {"auto", "uniform", "curvature", "bend", "film"}
        Arc-length density of the shape parametrisation (and hence of modes and panels):
        uniform; built from the seed's curvature (:func:`bem.shape.equidistributing_density`,
        concentrates on sharp bends); or from the lubrication weight (h + h_min)^(-1/2) of the
        gap h = 1 - r (:func:`bem.shape.film_density`, concentrates on the thin film and its
        entrance/exit); or "bend", the curvature density with a curvature-gradient term
        (``equidistributing_density(..., gradient=1)``, concentrates also on the ends of the
        film of a long vesicle, where a cap meets the cylindrical body). "auto" (default):
        "film" for lam/lam_c >= NEAR_CRITICAL (0.9) unless the vesicle is long (estimated
        ℓ ≈ ℓc λ/λc > LONG_VESICLE = 5), else "bend". With ``initial`` a curve or a
        VesicleResult, the density is re-built on that shape: re-solving a long vesicle from
        its own result (``initial=result, n_modes=...``) resolves it better than the density
        of the lubrication seed (at (0.6, 1.94), 64 modes: residual 8.2e-4 instead of 2.7e-3).
    density_terms : int
        Cosine terms of that density (ignored for "uniform").
    continuation : bool, optional
        Reach lam/lam_c > NEAR_CRITICAL through rungs 1 - lam/lam_c = 0.1, 0.05, 0.025, ...
        (each a ``rung_modes`` solve started from the previous one, the first from
        lubrication); a cold start from the lubrication shape there can drift to a spurious,
        closing film. Default: on when ``initial`` is None, lam/lam_c > NEAR_CRITICAL and the
        estimated length is at most RUNG_MAX_LENGTH = 9 R (a longer one, ν ≈ 0.6 near lam_c,
        is led astray by the rungs and converges from the lubrication shape at its own λ).
    rung_modes : int
        Shape modes of each continuation rung.
    valley : bool, optional
        Solve each level with :func:`bem.newton.valley_levenberg_marquardt` (directional
        Jacobian updates and extrapolation along the slow cap-to-cap mode) instead of
        :func:`bem.newton.levenberg_marquardt`. Default: on for a long vesicle, whose plain
        solve stops far from the minimum (at (0.6, 1.94): γ_max 799 instead of 932).
    max_time : float, optional
        Wall-time budget [s] (:class:`lubrication.checks.Deadline`), tested between BEM
        evaluations, levels and continuation rungs; when spent the result has status
        TIME_LIMIT. Default: no limit. Mode counts are at most MAX_MODES = 96.
    branch : {"parachute", "bullet"}, optional
        Shape class to return where two steady states coexist: only stored shapes of that
        class are tried as starts, and a solve that ends in the other class does not count as
        converged. Default: the state reached from the nearest stored shape.
    seed_bank : bool
        Try the seed bank's shapes (default). False: the solver's own seed only, a solve that
        depends on no stored solution.

    Returns
    -------
    VesicleResult
        ``status`` and the reason in ``message``: NO_STEADY_STATE when the membrane
        self-intersects or the film closes, TIME_LIMIT, NOT_CONVERGED when Levenberg–Marquardt
        or the steady residual fell short, UNRESOLVED when the estimated discretisation error
        is above the tolerance (of several, the first in this order), REJECTED_START when no
        level could start from its seed.

    Raises
    ------
    InvalidParameterError, CannotPassError
        Bad input; lam >= lam_c(nu).
    """
    (nu, lam, lam_c, ca_b, *_) = check_vesicle_inputs(
        nu, lam, lam_ratio=lam_ratio, ca_b=ca_b, n_modes=n_modes, tol=tol,
        tension_tol=tension_tol, residual_tol=residual_tol, max_modes=max_modes,
        rung_modes=rung_modes, density_terms=density_terms, max_iter=max_iter,
        max_time=max_time)
    if branch is not None and branch not in SHAPE_CLASSES:
        raise InvalidParameterError("branch", branch, '"parachute", "bullet" or None')
    t_start = time.perf_counter()
    deadline = Deadline(max_time)
    options = dict(ca_b=ca_b, n_modes=n_modes, tol=tol, tension_tol=tension_tol,
                   residual_tol=residual_tol, max_modes=max_modes, order=order, xtol=xtol,
                   max_iter=max_iter, density=density, density_terms=density_terms,
                   continuation=continuation, rung_modes=rung_modes, valley=valley)

    def solve(start):
        return _solve_from(nu, lam, initial=start, max_time=deadline.remaining(), **options)

    def done(res: VesicleResult, **changes) -> VesicleResult:
        timings = {**res.timings, "total_s": time.perf_counter() - t_start}
        return dataclasses.replace(res, timings=timings, **changes)

    ratio = lam / lam_c
    starts = ([("initial", lambda: initial)] if initial is not None
              else _starts(nu, lam, ratio, ca_b, branch, seed_bank))
    failures, found, res = [], [], None
    for label, make in starts:
        if deadline.expired():
            failures.append(f"{label}: not tried, {deadline.message()}")
            found.append(Status.TIME_LIMIT)
            break
        try:
            res = solve(make())
        except InvalidParameterError as exc:
            if label in ("own", "initial"):
                raise
            failures.append(f"{label}: cannot start ({exc})")   # its modes do not close here
            found.append(Status.REJECTED_START)
            continue
        if res.success and branch not in (None, res.shape_class):
            failures.append(f"{label}: converged to a {res.shape_class}, not a {branch}")
            found.append(Status.NOT_CONVERGED)
            continue
        if res.success:
            seed = res.seed if label in ("own", "initial") else label
            other = {} if (branch or initial is not None or not seed_bank
                           or deadline.expired()) else \
                _other_branch(nu, lam, ratio, ca_b, res, solve)
            message = res.message
            if other:
                message += (f"; bistable: a {other['shape_class']} steady state also exists "
                            f"here (V/U {other['V_over_U']:.6g}), ask for it with "
                            f"branch={other['shape_class']!r}")
            return done(res, seed=seed, other_branch=other, message=message,
                        failed_starts=failures)
        failures.append(f"{label}: {res.message}")
        found.append(res.status)
    status = leading_status(found) if found else Status.REJECTED_START
    message = "; ".join(failures) if failures else "no start"
    log.warning("solve_vesicle(nu=%g, lam=%g): %s", nu, lam, message)
    if res is None:
        return VesicleResult(nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=status,
                             message=message, tol=tol, residual_tol=residual_tol,
                             timings={"total_s": time.perf_counter() - t_start})
    return done(res, status=status, message=message, failed_starts=failures)


@single_threaded_blas()
def mode_convergence(result, modes, *, density: str | None = "bend", density_terms: int = 16,
                     xtol: float = 1e-9, max_iter: int = 40, progress=None) -> list[dict]:
    r"""Mesh-convergence study of a steady vesicle at a *fixed* parametrisation density.

    The arc-length density (with it the panel breaks) is part of the discretisation: the
    levels of :func:`solve_vesicle` each carry the density of their seed, and a long vesicle's
    default density is built on the lubrication shape, which does not resolve the BEM shape's
    rear film neck (at (0.6, 1.94), 64 modes: residual 2.7e-3 against 7.7e-4 with the density
    built on the BEM shape). Here the density is built once on ``result``'s shape and every
    level in ``modes`` (solved in the given order, each started from the previous one, the
    first from ``result``) is a Levenberg–Marquardt minimum with that density
    (:func:`bem.newton.valley_levenberg_marquardt`, full Jacobian budget), so the successive
    differences measure the discretisation error alone.

    Parameters
    ----------
    result : VesicleResult
        A solved vesicle (its shape seeds the first level; its density is re-built on it).
    modes : sequence of int
        Shape modes of the levels (8 to 256 each), e.g. (56, 64, 72, 80).
    density : {"bend", "curvature", "film"} or None
        Density built on ``result``'s shape; None keeps ``result``'s own density.
    density_terms, xtol, max_iter
        As in :func:`solve_vesicle`.
    progress : callable, optional
        Called with each finished row (e.g. ``print``).

    Returns
    -------
    list of dict
        One row per level: ``modes``, ``V_over_U``, ``dp_plus_R0``, ``tension_max``,
        ``film_min``, ``ell``, ``residual``, ``evaluations``, ``seconds``, ``success``,
        ``message``; from the third row on ``ratio_<key>`` =
        :math:`|q_k - q_{k-1}|/|q_{k-1} - q_{k-2}|` for V/U, Δp⁺ and γ_max (the observed
        contraction per level: a constant ratio ρ < 1 is geometric (spectral) convergence,
        and the error of the last level is about ρ/(1 - ρ) times its last difference).
    """
    if not isinstance(result, VesicleResult) or result.modes.size == 0:
        raise InvalidParameterError("result", type(result).__name__,
                                    "a VesicleResult with a shape")
    if density is not None and density not in _DENSITIES:
        raise InvalidParameterError("density", density, '"bend", "curvature", "film" or None')
    levels = [int(check_range("modes", n, 8, 256)) for n in modes]
    if not levels:
        raise InvalidParameterError("modes", modes, "at least one mode count")
    prev = result.curve()
    dens = prev.density if density is None else \
        _DENSITIES[density](prev, int(check_range("density_terms", density_terms, 1, 64)))
    rows = []
    for n in levels:
        seed = fit_curve(prev.sample, 0.0, 1.0, n, density=dens)
        t0 = time.perf_counter()
        st, op, info = _solve_level(result.nu, result.lam, result.ca_b,
                                    vesicle_discretisation(n), seed, n, xtol=xtol,
                                    max_iter=max_iter, valley=True)
        out = _outputs(result.nu, result.lam, op, st)
        row = {"modes": n, **{k: out[k] for k in (*_KEYS, "film_min", "ell", "residual")},
               "evaluations": info["evaluations"], "seconds": time.perf_counter() - t0,
               "success": info["success"], "message": info["message"]}
        if len(rows) >= 2:
            for k in _KEYS:
                d0 = rows[-1][k] - rows[-2][k]
                row[f"ratio_{k}"] = abs(row[k] - rows[-1][k]) / abs(d0) if d0 else math.nan
        rows.append(row)
        prev = st["curve"]
        if progress is not None:
            progress(row)
    return rows


def _profile(curve: SpectralCurve, g, n: int = 201) -> dict:
    """Shape and tension at ``n`` points equally spaced in arc length, poles included."""
    tt = np.linspace(0.0, 1.0, 4001)
    s_dense = curve.arc_length(tt)
    s = np.linspace(0.0, curve.length, n)
    tau = np.interp(s, s_dense, tt)
    for _ in range(3):
        tau = np.clip(tau - (curve.arc_length(tau) - s) / (curve.length * curve.g(tau)), 0, 1)
    x, r = curve.position(tau)
    r[0] = r[-1] = 0.0
    gam, dgam = tension_profile(curve, g, tau)
    return {"s": s, "x": x - x[0], "r": r, "psi": curve.tangent_angle(tau), "tension": gam,
            "shear_membrane": -dgam}
