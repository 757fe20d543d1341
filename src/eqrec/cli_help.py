"""The long help text of ``eqrec design`` (the system-file keys, the word conventions, the JSON keys).

Kept apart from :mod:`eqrec.cli` so that the command's code reads on one screen; ``%(limit)d``, ``%(seq)d``,
``%(print)d``, ``%(minutes)d`` and ``%(mem)d`` are filled in by :func:`eqrec.cli._system_help`.
"""

SYSTEM_HELP = """\
SYSTEM.yaml keys (matrices as nested lists):
  A      n x n state matrix                       (required)
  C      p x n output matrix                      (required)
  E      n x nw process-noise gain                (required)
  eta_w  bound on |w(t)|_inf, or one bound per    (required)
         column of E: [1, 0.5, 2] means |w_i(t)| <= eta_w[i]
  eta_v  bound on |v(t)|_inf, or one per column of V  (required)
  T      recovery time (default: the word length)
  B, f   input matrix and affine term (do not affect the design)
  V      p x nv measurement-noise gain (default identity)
  gaussian  Qw, Qv, x0_cov for the Kalman/LMV filters (eqrec compare only)

Words (--words) are strings over {0,1}: character t is 1 if the measurement
of time t (0-based) arrives, 0 if it is missing; all words must have length T.
Delay words (--delays, --method delay) are digit strings: character t is the
delay of the measurement of time t (0 = on time); a delay that reaches past
the horizon (t + delay >= T) means missing. --max-delay D --horizon T designs
for all (D+1)^T delay words. Words with equal event sequences are merged.
--max-lost m (with --max-delay D --horizon T; 0..T) is the loss-aware
language: each measurement has a delay 0..D or is lost (never arrives), at
most m lost per block; a delay past the horizon is missing in the block but
is not a loss (m = 0: no loss, m = T: every arrival pattern). The class
engine builds it without listing its words (window rule: at time k at most m
of the measurements of times <= k - D are missing); listed words (small
languages, --node-gains, --engine tree) write a lost measurement as x.

Output JSON: method, T, mu1, mu2 (optimum), certified_mu2 (worst case recomputed
from the gains alone), certified_terminal (the worst case of the error norm
||x(T) - xhat(T)||_inf at the end of the horizon, over every word, recomputed
from the gains alone: equalized recovery holds when it is at most mu1, so the
gains can be reused every T steps), solver, status, words, gains: for each
designed word
{"F": (T*n x T*p), "u0": (T*n)} in the convention
  ue(t) = u0(t) + sum_{tau<=t} F(t,tau) y_xi(tau),
  xhat(t+1) = A xhat + B u - ue + f,
  y_xi(tau) = y(tau) - C xhat(tau) if y(tau) has arrived by time t, else 0
(F(t,tau) is zero wherever y(tau) has not arrived by time t).
--method prefix and time add engine (classes or tree), for the class engine
classes (below), and with --mu1 free (mu1 = the smallest feasible mu1)
mu1_free {route, mu1_min {upper (attained by certified gains), lower (proven
infeasible), binding (the terminal class and row that set it)}}.
Last, system: the system file's matrices (E and V with per-channel bounds
folded in), so that eqrec.load_design(path) reads the design back into
Python, its estimator giving the same estimates and bounds.

State weights (--state-weights w1,...,wn; methods time, prefix, delay): the
design is made on z = W x, W = diag(w), so mu1, mu2, every level and every
certified value bound max_i w_i |x_i - xhat_i| instead of the plain infinity
norm (|x_i - xhat_i| <= level / w_i). The JSON adds state_weights; its gains
(F, u0, K) are written in the file's state x, with the conventions above.

Engines (--engine, methods prefix and delay; default classes): the class
engine solves one small LP per (time d, available data S) class and state
row (nodes of the prefix tree that see the same data at the same time share
their level) and derives the node gains from the class gains K; the tree
engine solves one LP with a gain row per prefix-tree node (the independent
cross-check).  Both give the same optimum.  For --max-delay D --horizon T the
class engine builds the classes from the window rule without enumerating the
(D+1)^T words: D = 4, T = 30 (9.3e20 words, 446 classes) takes seconds and
writes about 1 MB.  --engine tree and --node-gains need the words enumerated
and are refused above %(limit)d words.

Class keys (class engine): classes, one row per class {class, k, data,
terminal, sequences, nodes, level, certified, K}.  The label "d:S" is the
time d and, as a 0/1 string over the times 0..d-1, the measurements received
by time d-1 (1: received; data lists their times).  The class-form estimator
  xhat(d) = xbar(d) + K (y_S - ybar_S)
(xbar, ybar the noise-free prediction from xhat(0), inputs and f included;
y_S stacks y(tau) for tau in S, by time then output; K is n x |S|p) has the
worst case "certified" (recomputed from K alone) at time d along every
sequence of the class; "level" is the designed level, at most mu1 for a
terminal class (where words end), "sequences" the class's weight in the sum
cost.

--method delay adds: engine, cost, J (the cost of --cost), J_certified,
sequences and nodes (of the reduced event language and its prefix tree),
classes (class engine), and with --mu1 free: mu1_free {route, J, lower_bound
(a certified lower bound of J over every mu1), gap, mu1_min}.  With node
gains (--node-gains; by default when the reduced language has at most %(seq)d
sequences) it also writes gains, levels (one row per event prefix and time:
designed level, certified worst case, sequences through it; a prefix is
labelled by its 0/1 word while no measurement has arrived late, else by its
events e_0.e_1...) and event_sequences (per designed sequence, for each time
t a 0/1 string over y(0..t): character tau is 1 if y(tau) is available at
time t).  words lists the delay words (designed_words the designed ones),
except for a --max-delay language left unenumerated: then words is the
number of words and designed_words is omitted (max_delay, horizon and, with
--max-lost, max_lost name the language).

Size and solves (--max-delay D --horizon T, class engine): before solving,
the design is estimated from its class sizes alone (classes, LP rows, time
and memory on this machine's cores; eqrec.design.inputs.estimate_delay_design)
and the estimate is printed when it exceeds %(print)d s.  A design estimated
past %(minutes)d min or past %(mem)d%% of the available memory is refused
(exit 1) unless --force.  The work grows about as T^3 (a class at time d
solves LPs of d measurements over d noise samples): on 2 quiet cores the
two-mass plant's D = 1 takes 2 s at T = 100, 26 s at T = 400 and 94 s at
T = 600 (benchmarks/bench_horizon.py).
Long stages show a progress bar on a terminal, one line each otherwise.
An LP that ends without a usable status (HiGHS 'Not Set' or 'Unknown' after
a numerical breakdown) is solved again with other settings (HiGHS defaults,
presolve off, primal simplex, interior point, a scaled model), then with
Clarabel; the summary and the JSON key solver_retries say which answered.
When all fail on a plant with spectral radius above 1 and a long --horizon
(or the design is found infeasible where the error maps grow past 1e8, a
verdict the LP cannot be trusted with), the message says the horizon is too
long for so unstable a plant and names the longest horizon that solves: a
bisection of at most 8 smaller designs and 120 s in all, each estimated
first and stopped when the time is up (eqrec.longest_horizon from Python).
"""
