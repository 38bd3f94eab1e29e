//! Algebraic loops: components whose direct feedthrough closes a cycle, solved by Newton's method
//! wherever the connections are propagated (every communication point, and each propagation in
//! Initialization Mode; FMI 3.0.2, the state Initialization Mode: "Artificial or real algebraic
//! loops over connected FMUs in Initialization Mode may be handled by using appropriate numerical
//! algorithms").
//!
//! The evaluation order (`Simulation::arrange`) is a topological sort of the direct-feedthrough
//! graph's strongly connected components (Tarjan's algorithm, a few lines below: no graph crate is
//! in the workspace's Cargo.lock, and the graph has one node per component). A component alone is
//! placed as before (the lowest system index whose feeding components are placed first), so a
//! system without a loop gets the order, the calls and the cost per step it got before loops were
//! solved. A component set of more than one member, or one whose output feeds its own feedthrough
//! input, is a loop (`Loop`), placed as one block.
//!
//! **Unknowns (tear variables): the loop's connected inputs**, one per connection between two of
//! its members into an input some output depends on directly; r(u) = u - g(u), where g(u) sets u
//! on every member (one fmi2SetReal each) and reads the members' connected outputs (one
//! fmi2GetReal each), the inputs' sources. Inputs rather than outputs because: the iterate is what
//! the master sets, as it is, and the first guess at a point is what the inputs hold (the previous
//! point's solution; at the start of a run their start values), whereas outputs read at a new point
//! come from inputs of the point before; and a component's block of the Jacobian is
//! d(outputs)/d(inputs), what fmi2GetDirectionalDerivative / fmi3GetDirectionalDerivative give
//! with an input as the known and a unit seed. The cost: an output feeding several inputs of the
//! loop is several unknowns (equal at the solution).
//!
//! **Newton's method**: J = I - dg/du, where dg_i/du_j is the derivative of the output feeding input
//! i with respect to input j of the same component (0 across components). Exact, one directional
//! derivative per unknown, when every member provides them (`providesDirectionalDerivative(s)`
//! of the interface it runs as) and the run does not ask for finite differences; otherwise a
//! forward difference per unknown (input j moved by sqrt(eps) max(|u_j|, 1), the component's
//! outputs read, the input set back). A step that does not lower the residual is halved, up to
//! four times. Converged when |r_i| <= atol + rtol |u_i| for every unknown, checked on the values
//! the components hold (the outputs read are those of the inputs set); failing: a singular
//! Jacobian, or no convergence within the iterations allowed, fails the run naming the loop's
//! components and unknowns, the residual and the time.
//!
//! Every buffer (unknowns, residuals, Jacobian, pivots, a column) is made when the simulation is
//! built: solving a loop allocates nothing.

use super::*;

/// How the algebraic loops are solved ([`RunOptions::loops`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LoopOptions {
    /// Relative tolerance on each unknown: |u_i - g_i(u)| <= atol + rtol |u_i| (default 1e-10).
    pub rtol: f64,
    /// Absolute tolerance, in the unknowns' units (default 1e-10).
    pub atol: f64,
    /// Newton iterations allowed at one propagation (default 20).
    pub max_iterations: usize,
    /// Finite differences even where every component of a loop gives directional derivatives.
    pub finite_differences: bool,
}

impl Default for LoopOptions {
    fn default() -> LoopOptions {
        LoopOptions {
            rtol: 1e-10,
            atol: 1e-10,
            max_iterations: 20,
            finite_differences: false,
        }
    }
}

/// What one loop took in a run ([`RunResult::loops`]).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LoopReport {
    /// The loop's components, in the system's order.
    pub components: Vec<String>,
    /// Its unknowns: "component.input".
    pub unknowns: Vec<String>,
    /// Whether the Jacobian was exact (directional derivatives) rather than finite differences.
    pub exact_jacobian: bool,
    /// Propagations that solved it.
    pub solves: usize,
    /// Newton iterations over the run, and the most in one solve.
    pub iterations: usize,
    pub most_iterations: usize,
    /// Evaluations of g (set the unknowns, read the outputs), Jacobian columns not counted.
    pub evaluations: usize,
}

impl std::fmt::Display for LoopReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "algebraic loop among {} ({} unknowns): {} Jacobian, {} solves, {} Newton iterations ({:.3} a solve, at most {}), {} residual evaluations",
            self.components.join(", "),
            self.unknowns.len(),
            if self.exact_jacobian {
                "exact (directional derivatives)"
            } else {
                "finite-difference"
            },
            self.solves,
            self.iterations,
            self.iterations as f64 / self.solves.max(1) as f64,
            self.most_iterations,
            self.evaluations
        )
    }
}

/// The unknowns of one member of a loop: its inputs fed from the loop, `u[first..first + vrs.len()]`.
#[derive(Default)]
struct Member {
    slave: usize,
    /// Its read port (every member's outputs feed the loop).
    read: usize,
    vrs: Vec<u32>,
    first: usize,
}

/// One algebraic loop and everything its solve needs, made when the simulation is built.
#[derive(Default)]
pub(super) struct Loop {
    /// Index in `Simulation::steps` of its first member (the members follow one another).
    pub(super) first_step: usize,
    members: Vec<Member>,
    /// For each unknown: its member, and (read port, index) of the output that feeds it.
    owner: Vec<usize>,
    source: Vec<(usize, usize)>,
    /// Connections between members into inputs without feedthrough: set once it is solved.
    after: Vec<Write>,
    report: LoopReport,
    u: Vec<f64>,
    g: Vec<f64>,
    r: Vec<f64>,
    step: Vec<f64>,
    /// Row-major n × n: I - dg/du, then its LU factors.
    jac: Vec<f64>,
    pivots: Vec<usize>,
    /// One component's connected outputs: a directional derivative or a perturbed read.
    column: Vec<f64>,
    /// The start of a run's first guess: each unknown's start value (the description's).
    starts: Vec<f64>,
}

/// The strongly connected components of the graph `edges` (node i -> each of edges[i]), Tarjan's
/// algorithm (recursive: the depth is at most the number of components of a system).
fn tarjan(edges: &[Vec<usize>]) -> Vec<Vec<usize>> {
    struct State<'a> {
        edges: &'a [Vec<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(s: &mut State, v: usize) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for k in 0..s.edges[v].len() {
            let w = s.edges[v][k];
            match s.index[w] {
                None => {
                    visit(s, w);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                Some(_) => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut scc = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack[w] = false;
                scc.push(w);
                if w == v {
                    break;
                }
            }
            scc.sort_unstable();
            s.out.push(scc);
        }
    }
    let n = edges.len();
    let mut s = State {
        edges,
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(&mut s, v);
        }
    }
    s.out
}

/// The evaluation order of components whose feeding components are `feeds[i]` (a source whose
/// output reaches an input of i with direct feedthrough), and the loops (sets of components, each
/// in the system's order, consecutive in the order). Each step places the block (a component, or
/// a loop) with the lowest system index among those whose feeding components outside it are
/// placed.
pub(super) fn order(feeds: &[Vec<usize>]) -> (Vec<usize>, Vec<Vec<usize>>) {
    let blocks = tarjan(feeds);
    let n = feeds.len();
    let mut block_of = vec![0; n];
    for (b, members) in blocks.iter().enumerate() {
        for &m in members {
            block_of[m] = b;
        }
    }
    let mut placed = vec![false; n];
    let mut order = Vec::with_capacity(n);
    let mut loops = Vec::new();
    while order.len() < n {
        let ready = (0..n)
            .filter(|&i| !placed[i])
            .find(|&i| {
                blocks[block_of[i]]
                    .iter()
                    .all(|&m| feeds[m].iter().all(|&s| placed[s] || block_of[s] == block_of[i]))
            })
            .expect("the components of a strongly connected component's condensation have a topological order");
        let members = &blocks[block_of[ready]];
        if members.len() > 1 || feeds[ready].contains(&ready) {
            loops.push(members.clone());
        }
        for &m in members {
            placed[m] = true;
            order.push(m);
        }
    }
    (order, loops)
}

impl Simulation {
    /// The evaluation order ([`order`]), each component's writes from components before it, the
    /// writes set last, and the loops; `pairs` as [`Simulation::writes`], `feeds` as [`order`].
    pub(super) fn arrange(&mut self, pairs: &Pairs, feeds: &[Vec<usize>]) -> Result<(), Error> {
        let (order, blocks) = order(feeds);
        let position = |i: usize| order.iter().position(|&s| s == i).expect("sorted");
        let mut block = vec![usize::MAX; self.slaves.len()];
        for (b, members) in blocks.iter().enumerate() {
            for &m in members {
                block[m] = b;
            }
        }
        // Within a loop a connection is the loop's: an unknown, or set once it is solved.
        let inside = |t: usize, s: usize| block[t] != usize::MAX && block[t] == block[s];
        for &c in &order {
            let before = pairs
                .iter()
                .enumerate()
                .filter(|(_, ((t, s), _))| *t == c && position(*s) < position(c) && !inside(*t, *s))
                .map(|(w, _)| w)
                .collect();
            self.steps.push((c, before));
        }
        self.late = pairs
            .iter()
            .enumerate()
            .filter(|(_, ((t, s), _))| position(*s) >= position(*t) && !inside(*t, *s))
            .map(|(w, _)| w)
            .collect();
        for members in &blocks {
            let lp = self.build_loop(members, pairs, position(members[0]))?;
            self.loops.push(lp);
        }
        Ok(())
    }

    fn build_loop(&self, members: &[usize], pairs: &Pairs, first_step: usize) -> Result<Loop, Error> {
        let mut lp = Loop {
            first_step,
            ..Loop::default()
        };
        for &c in members {
            let fmu = self.fmu_of(c);
            let read = self.read_of[c].expect("a member of a loop feeds one");
            let mut member = Member {
                slave: c,
                read,
                vrs: Vec::new(),
                first: lp.owner.len(),
            };
            for ((t, s), list) in pairs.iter().filter(|((t, s), _)| *t == c && members.contains(s)) {
                let source = self.read_of[*s].expect("a source has a read port");
                let mut later = Vec::new();
                for &(tvr, svr) in list {
                    let idx = self.reads[source].vrs.iter().position(|v| *v == svr).expect("read");
                    if fmu.feedthrough.contains(&tvr) {
                        let v = fmu
                            .description
                            .variables
                            .iter()
                            .find(|v| v.vr == tvr && v.ty == Type::Real);
                        lp.report.unknowns.push(format!(
                            "{}.{}",
                            self.slaves[c].name,
                            v.map_or("?", |v| v.name.as_str())
                        ));
                        lp.starts.push(v.and_then(|v| v.start_real()).unwrap_or(0.0));
                        member.vrs.push(tvr);
                        lp.owner.push(lp.members.len());
                        lp.source.push((source, idx));
                    } else {
                        later.push((tvr, idx));
                    }
                }
                if !later.is_empty() {
                    let n = later.len();
                    lp.after.push(Write {
                        port: Port {
                            slave: *t,
                            vrs: later.iter().map(|(v, _)| *v).collect(),
                            buf: vec![0.0; n],
                        },
                        source: self.read_of[*s].expect("a source has a read port"),
                        idx: later.iter().map(|(_, i)| *i).collect(),
                    });
                }
            }
            lp.members.push(member);
        }
        lp.report.components = members.iter().map(|&c| self.slaves[c].name.clone()).collect();
        let n = lp.owner.len();
        let widest = lp
            .members
            .iter()
            .map(|m| self.reads[m.read].vrs.len())
            .max()
            .unwrap_or(0);
        lp.u = lp.starts.clone();
        lp.g = vec![0.0; n];
        lp.r = vec![0.0; n];
        lp.step = vec![0.0; n];
        lp.jac = vec![0.0; n * n];
        lp.pivots = vec![0; n];
        lp.column = vec![0.0; widest];
        Ok(lp)
    }

    /// The algebraic loops: (components, unknowns "component.input") of each.
    pub fn algebraic_loops(&self) -> Vec<(Vec<String>, Vec<String>)> {
        self.loops
            .iter()
            .map(|l| (l.report.components.clone(), l.report.unknowns.clone()))
            .collect()
    }

    /// The loops' components, for messages: "[a, b], [c]".
    pub(super) fn loops_named(&self) -> String {
        let names: Vec<String> = self
            .loops
            .iter()
            .map(|l| format!("[{}]", l.report.components.join(", ")))
            .collect();
        names.join(", ")
    }

    /// What each loop took since the run began (none with [`Scheme::Jacobi`]: it solves none).
    pub(super) fn loop_reports(&self) -> Vec<LoopReport> {
        match self.scheme {
            Scheme::GaussSeidel => self.loops.iter().map(|l| l.report.clone()).collect(),
            Scheme::Jacobi => Vec::new(),
        }
    }

    /// At the start of a run: each loop's first guess (the unknowns' start values, or the values
    /// the run sets on them), its counts cleared, and the kind of its Jacobian chosen.
    pub(super) fn reset_loops(&mut self, values: &[(String, Target, Setter)]) {
        for k in 0..self.loops.len() {
            let exact = !self.loop_options.finite_differences
                && self.loops[k].members.iter().all(|m| {
                    let s = &self.slaves[m.slave];
                    let d = &self.fmus[s.fmu].description;
                    if s.me {
                        d.me.as_ref().is_some_and(|me| me.provides_directional_derivative)
                    } else {
                        d.cs.as_ref().is_some_and(|cs| cs.provides_directional_derivative)
                    }
                });
            let lp = &mut self.loops[k];
            for i in 0..lp.u.len() {
                let m = &lp.members[lp.owner[i]];
                let vr = m.vrs[i - m.first];
                lp.u[i] = values
                    .iter()
                    .rev()
                    .find_map(|(_, t, v)| match v {
                        Setter::Real(x) if t.slave == m.slave && t.vr == vr => Some(*x),
                        _ => None,
                    })
                    .unwrap_or(lp.starts[i]);
            }
            let (components, unknowns) = (
                std::mem::take(&mut lp.report.components),
                std::mem::take(&mut lp.report.unknowns),
            );
            lp.report = LoopReport {
                components,
                unknowns,
                exact_jacobian: exact,
                ..LoopReport::default()
            };
        }
    }

    /// [`Simulation::propagate_values`] in dependency order with loops: each loop solved at its
    /// place in the order.
    pub(super) fn propagate_with_loops(&mut self, t: f64) -> Result<(), Error> {
        let mut i = 0;
        let mut next = 0;
        while i < self.steps.len() {
            if next < self.loops.len() && self.loops[next].first_step == i {
                for m in 0..self.loops[next].members.len() {
                    self.typed_inputs(self.steps[i + m].0, t)?;
                    for j in 0..self.steps[i + m].1.len() {
                        let w = self.steps[i + m].1[j];
                        self.write(w, t)?;
                    }
                }
                let mut lp = std::mem::take(&mut self.loops[next]);
                let r = self.solve(&mut lp, t);
                let members = lp.members.len();
                self.loops[next] = lp;
                r?;
                for m in 0..members {
                    self.typed_outputs(self.steps[i + m].0, t)?;
                }
                i += members;
                next += 1;
                continue;
            }
            self.exchange_at_step(i, t)?;
            i += 1;
        }
        self.exchange_late(t)
    }

    /// g(`lp.u`) into `lp.g`, the residual into `lp.r`; returns the scaled residual
    /// max |r_i| / (atol + rtol |u_i|) (converged: <= 1).
    fn evaluate(&mut self, lp: &mut Loop, t: f64) -> Result<f64, Error> {
        for m in &lp.members {
            let s = &mut self.slaves[m.slave];
            s.instance
                .as_mut()
                .expect("instantiated")
                .set_real(&m.vrs, &lp.u[m.first..m.first + m.vrs.len()])
                .map_err(|e| Error::fmi(&s.name, fname(s.v3, "fmi2SetReal"), &e, Some(t), "algebraic loop"))?;
        }
        for m in 0..lp.members.len() {
            self.read(lp.members[m].read, t)?;
        }
        lp.report.evaluations += 1;
        let o = self.loop_options;
        let mut worst = 0.0f64;
        for i in 0..lp.u.len() {
            let (r, k) = lp.source[i];
            lp.g[i] = self.reads[r].buf[k];
            lp.r[i] = lp.u[i] - lp.g[i];
            let scaled = lp.r[i].abs() / (o.atol + o.rtol * lp.u[i].abs());
            // NaN counts as not converged (and fails at the Jacobian or the iteration limit).
            worst = if scaled.is_nan() {
                f64::INFINITY
            } else {
                worst.max(scaled)
            };
        }
        Ok(worst)
    }

    /// `lp.jac` = I - dg/du at the current unknowns (the components hold them and their outputs).
    fn jacobian(&mut self, lp: &mut Loop, t: f64) -> Result<(), Error> {
        let n = lp.u.len();
        lp.jac.fill(0.0);
        for j in 0..n {
            let m = &lp.members[lp.owner[j]];
            let vr = [m.vrs[j - m.first]];
            let width = self.reads[m.read].vrs.len();
            let column = &mut lp.column[..width];
            let s = &mut self.slaves[m.slave];
            let inst = s.instance.as_mut().expect("instantiated");
            let delta = f64::EPSILON.sqrt() * lp.u[j].abs().max(1.0);
            if lp.report.exact_jacobian {
                inst.get_directional_derivative(Directional {
                    unknowns: &self.reads[m.read].vrs,
                    knowns: &vr,
                    seed: &[1.0],
                    out: column,
                })
                .map_err(|e| {
                    Error::fmi(
                        &s.name,
                        fname(s.v3, "fmi2GetDirectionalDerivative"),
                        &e,
                        Some(t),
                        "algebraic loop's Jacobian",
                    )
                })?;
            } else {
                // The message is made only on a failure: a column allocates nothing.
                let (name, v3) = (&s.name, s.v3);
                let fail = |f: &'static str| {
                    move |e| Error::fmi(name, fname(v3, f), &e, Some(t), "algebraic loop's finite differences")
                };
                inst.set_real(&vr, &[lp.u[j] + delta]).map_err(fail("fmi2SetReal"))?;
                inst.get_real(&self.reads[m.read].vrs, column)
                    .map_err(fail("fmi2GetReal"))?;
                inst.set_real(&vr, &[lp.u[j]]).map_err(fail("fmi2SetReal"))?;
            }
            for i in 0..n {
                let (r, k) = lp.source[i];
                if r == m.read {
                    let d = if lp.report.exact_jacobian {
                        column[k]
                    } else {
                        (column[k] - lp.g[i]) / delta
                    };
                    lp.jac[i * n + j] -= d;
                }
            }
            lp.jac[j * n + j] += 1.0;
        }
        // Finite differences read into `column` and set each input back: the read ports still
        // hold g(u) and the components u.
        Ok(())
    }

    /// Newton's method on r(u) = u - g(u) (see the module); the components end holding the
    /// converged unknowns and their outputs, then the loop's other connections are set.
    fn solve(&mut self, lp: &mut Loop, t: f64) -> Result<(), Error> {
        let n = lp.u.len();
        let mut norm = self.evaluate(lp, t)?;
        let mut iterations = 0;
        while norm > 1.0 {
            if iterations == self.loop_options.max_iterations {
                return Err(self.loop_failure(
                    lp,
                    t,
                    &format!(
                        "Newton's method did not converge in {iterations} iterations (scaled residual {norm:.3e})"
                    ),
                ));
            }
            self.jacobian(lp, t)?;
            if !lu(&mut lp.jac, n, &mut lp.pivots) {
                return Err(self.loop_failure(
                    lp,
                    t,
                    "its Jacobian I - dg/du is singular: the loop has no unique solution here",
                ));
            }
            for i in 0..n {
                lp.step[i] = -lp.r[i];
            }
            lu_solve(&lp.jac, n, &lp.pivots, &mut lp.step);
            iterations += 1;
            let mut lambda = 1.0;
            for halving in 0..=4 {
                for i in 0..n {
                    lp.u[i] += lambda * lp.step[i];
                }
                let trial = self.evaluate(lp, t)?;
                if trial < norm || trial <= 1.0 || halving == 4 {
                    norm = trial;
                    break;
                }
                for i in 0..n {
                    lp.u[i] -= lambda * lp.step[i];
                }
                lambda /= 2.0;
            }
        }
        lp.report.solves += 1;
        lp.report.iterations += iterations;
        lp.report.most_iterations = lp.report.most_iterations.max(iterations);
        for w in &mut lp.after {
            let src = &self.reads[w.source].buf;
            for (j, &i) in w.idx.iter().enumerate() {
                w.port.buf[j] = src[i];
            }
            let s = &mut self.slaves[w.port.slave];
            s.instance
                .as_mut()
                .expect("instantiated")
                .set_real(&w.port.vrs, &w.port.buf)
                .map_err(|e| Error::fmi(&s.name, fname(s.v3, "fmi2SetReal"), &e, Some(t), "connected inputs"))?;
        }
        Ok(())
    }

    fn loop_failure(&self, lp: &Loop, t: f64, why: &str) -> Error {
        let (worst, at) = lp.r.iter().enumerate().fold((0.0f64, 0), |(w, k), (i, r)| {
            if r.abs() > w || r.is_nan() {
                (r.abs(), i)
            } else {
                (w, k)
            }
        });
        Error {
            component: lp.report.components.first().cloned(),
            time: Some(t),
            ..Error::new(
                crate::ErrorKind::Loop,
                format!(
                    "system '{}': algebraic loop among components {} (unknowns {}) at t = {t} s: {why}; residual max |u - g(u)| = {worst:.3e} (at {}; 2-norm {:.3e}; tolerance atol {:e} + rtol {:e} |u|; {} Jacobian)",
                    self.name,
                    lp.report.components.join(", "),
                    lp.report.unknowns.join(", "),
                    lp.report.unknowns.get(at).map_or("?", String::as_str),
                    lp.r.iter().map(|r| r * r).sum::<f64>().sqrt(),
                    self.loop_options.atol,
                    self.loop_options.rtol,
                    if lp.report.exact_jacobian {
                        "exact"
                    } else {
                        "finite-difference"
                    }
                ),
            )
        }
    }
}

/// LU factorization with partial pivoting of the row-major n × n `a`, in place (rows swapped as
/// LAPACK's getrf does, `pivots[k]` the row swapped with k); false if a pivot is zero to working
/// precision (|p| <= n eps max|a|) or not a number.
fn lu(a: &mut [f64], n: usize, pivots: &mut [usize]) -> bool {
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))
            .expect("k < n");
        pivots[k] = p;
        let pivot = a[p * n + k].abs();
        if pivot.is_nan() || pivot <= scale * n as f64 * f64::EPSILON {
            return false;
        }
        if p != k {
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
        }
        for i in k + 1..n {
            let f = a[i * n + k] / a[k * n + k];
            a[i * n + k] = f;
            for j in k + 1..n {
                a[i * n + j] -= f * a[k * n + j];
            }
        }
    }
    true
}

/// Solves a x = b with the factors of [`lu`]; x in `b`.
fn lu_solve(a: &[f64], n: usize, pivots: &[usize], b: &mut [f64]) {
    for (k, &p) in pivots.iter().enumerate().take(n) {
        b.swap(k, p);
    }
    for i in 0..n {
        for k in 0..i {
            b[i] -= a[i * n + k] * b[k];
        }
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            b[i] -= a[i * n + k] * b[k];
        }
        b[i] /= a[i * n + i];
    }
}
