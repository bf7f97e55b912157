//! Anderson mixing (Walker & Ni 2011, "Anderson acceleration for fixed-point iterations") for a
//! fixed-point problem `u = G(u)` with residual `r = G(u) - u`. History of `mem` differences in a
//! ring buffer, Gram matrix updated incrementally: O(mem M) per step, no allocation per step.

#[derive(Debug, Clone)]
pub(crate) struct Anderson {
    mem: usize,
    beta: f64,
    du: Vec<Vec<f64>>,
    dr: Vec<Vec<f64>>,
    gram: Vec<f64>,
    u_prev: Vec<f64>,
    r_prev: Vec<f64>,
    have_prev: bool,
    len: usize,
    head: usize,
    // small dense system
    a: Vec<f64>,
    b: Vec<f64>,
    idx: Vec<usize>,
}

impl Anderson {
    pub fn new(m: usize, mem: usize, beta: f64) -> Self {
        Self {
            mem,
            beta,
            du: vec![vec![0.0; m]; mem],
            dr: vec![vec![0.0; m]; mem],
            gram: vec![0.0; mem * mem],
            u_prev: vec![0.0; m],
            r_prev: vec![0.0; m],
            have_prev: false,
            len: 0,
            head: 0,
            a: vec![0.0; mem * mem],
            b: vec![0.0; mem],
            idx: vec![0; mem],
        }
    }

    /// Changes the mixing parameter.
    pub fn set_beta(&mut self, beta: f64) {
        self.beta = beta;
    }

    /// Forget the history (after a rejected step).
    pub fn reset(&mut self) {
        self.have_prev = false;
        self.len = 0;
        self.head = 0;
    }

    /// Replaces `u` (the current iterate, residual `r`) by the next iterate.
    pub fn step(&mut self, u: &mut [f64], r: &[f64]) {
        let mem = self.mem;
        if self.have_prev && mem > 0 {
            let slot = self.head;
            {
                let du = &mut self.du[slot];
                let dr = &mut self.dr[slot];
                for i in 0..u.len() {
                    du[i] = u[i] - self.u_prev[i];
                    dr[i] = r[i] - self.r_prev[i];
                }
            }
            self.head = (self.head + 1) % mem;
            self.len = (self.len + 1).min(mem);
            for k in 0..mem {
                if k < self.len || k == slot {
                    let v = dot(&self.dr[slot], &self.dr[k]);
                    self.gram[slot * mem + k] = v;
                    self.gram[k * mem + slot] = v;
                }
            }
        }
        self.u_prev.copy_from_slice(u);
        self.r_prev.copy_from_slice(r);
        self.have_prev = true;

        let n = self.len;
        // Slots in use: the last n written.
        for j in 0..n {
            self.idx[j] = (self.head + mem - n + j) % mem;
        }
        let mut coef_ok = n > 0;
        if n > 0 {
            let mut trace = 0.0;
            for j in 0..n {
                let sj = self.idx[j];
                self.b[j] = dot(&self.dr[sj], r);
                for k in 0..n {
                    self.a[j * n + k] = self.gram[sj * mem + self.idx[k]];
                }
                trace += self.a[j * n + j];
            }
            let reg = 1e-12 * trace / n as f64;
            for j in 0..n {
                self.a[j * n + j] += reg;
            }
            coef_ok = solve(&mut self.a[..n * n], &mut self.b[..n], n) && trace > 0.0;
        }
        let beta = self.beta;
        for i in 0..u.len() {
            u[i] += beta * r[i];
        }
        if coef_ok {
            for j in 0..n {
                let c = self.b[j];
                let sj = self.idx[j];
                let du = &self.du[sj];
                let dr = &self.dr[sj];
                for i in 0..u.len() {
                    u[i] -= c * (du[i] + beta * dr[i]);
                }
            }
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Gaussian elimination with partial pivoting on an n x n row-major system; false if singular.
fn solve(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    for c in 0..n {
        let mut p = c;
        for r in c + 1..n {
            if a[r * n + c].abs() > a[p * n + c].abs() {
                p = r;
            }
        }
        if a[p * n + c] == 0.0 || !a[p * n + c].is_finite() {
            return false;
        }
        if p != c {
            for k in 0..n {
                a.swap(c * n + k, p * n + k);
            }
            b.swap(c, p);
        }
        for r in c + 1..n {
            let f = a[r * n + c] / a[c * n + c];
            for k in c..n {
                a[r * n + k] -= f * a[c * n + k];
            }
            b[r] -= f * b[c];
        }
    }
    for c in (0..n).rev() {
        let mut s = b[c];
        for k in c + 1..n {
            s -= a[c * n + k] * b[k];
        }
        b[c] = s / a[c * n + c];
    }
    b[..n].iter().all(|v| v.is_finite())
}
