//! The `.bpt` patch text format: Newell's Utah format with an extension for rational and
//! trimmed patches.
//!
//! The classic file (as the Utah teapot is distributed) is a patch count, then per patch the
//! degrees `3 3` and 16 control points `x y z`, row-major (`P_00 P_01 … P_33`, see
//! [`super::model`]). Everything is whitespace-separated numbers, so line breaks do not matter.
//! The extension adds, after a patch's 16 points, optionally:
//!
//! ```text
//! weights W00 W01 … W33       # 16 positive weights: a rational patch
//! trim K U1 V1 … UK VK        # a trim loop of K ≥ 3 (u, v) points in [0, 1]², closed
//! ```
//!
//! (`weights` at most once, `trim` any number of times) and `#` comments to the end of a line.
//! A classic file is a valid extended file, and an extended file without those lines is
//! classic. Errors are one line, `NAME:LINE: what`.

use super::model::{Patch, PatchModel, TrimLoop};

/// A token with the 1-based line it is on.
struct Token<'a> {
    text: &'a str,
    line: usize,
}

struct Tokens<'a> {
    tokens: Vec<Token<'a>>,
    next: usize,
    name: &'a str,
    last_line: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str, name: &'a str) -> Self {
        let mut tokens = Vec::new();
        let mut last_line = 1;
        for (i, raw) in text.lines().enumerate() {
            last_line = i + 1;
            let line = raw.split('#').next().unwrap_or("");
            tokens.extend(
                line.split_whitespace()
                    .map(|text| Token { text, line: i + 1 }),
            );
        }
        Tokens {
            tokens,
            next: 0,
            name,
            last_line,
        }
    }

    fn error_at(&self, line: usize, what: impl std::fmt::Display) -> String {
        format!("{}:{line}: {what}", self.name)
    }

    fn peek(&self) -> Option<&Token<'a>> {
        self.tokens.get(self.next)
    }

    /// The next token, or an error naming what was expected at the end of the file.
    fn take(&mut self, expected: &str) -> Result<&Token<'a>, String> {
        match self.tokens.get(self.next) {
            Some(t) => {
                self.next += 1;
                Ok(t)
            }
            None => Err(self.error_at(
                self.last_line,
                format!("file ends where {expected} was expected"),
            )),
        }
    }

    fn number(&mut self, expected: &str) -> Result<(f64, usize), String> {
        let t = self.take(expected)?;
        let (text, line) = (t.text, t.line);
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok((v, line)),
            _ => Err(self.error_at(line, format!("{expected}: '{text}' is not a finite number"))),
        }
    }

    fn count(&mut self, expected: &str) -> Result<(usize, usize), String> {
        let t = self.take(expected)?;
        let (text, line) = (t.text, t.line);
        text.parse::<usize>()
            .map(|n| (n, line))
            .map_err(|_| self.error_at(line, format!("{expected}: '{text}' is not a whole number")))
    }
}

/// Whether segments `a–b` and `c–d` cross or touch (collinear overlaps included).
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let orient = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        let x = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
        if x > 0.0 {
            1
        } else if x < 0.0 {
            -1
        } else {
            0
        }
    };
    let within = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    let (o1, o2, o3, o4) = (
        orient(a, b, c),
        orient(a, b, d),
        orient(c, d, a),
        orient(c, d, b),
    );
    if o1 != o2 && o3 != o4 {
        return true;
    }
    (o1 == 0 && within(a, b, c))
        || (o2 == 0 && within(a, b, d))
        || (o3 == 0 && within(c, d, a))
        || (o4 == 0 && within(c, d, b))
}

/// Why a trim loop is not simple, or `None` when no two non-adjacent edges meet and adjacent
/// edges meet only at their shared vertex.
fn self_crossing(t: &TrimLoop) -> Option<String> {
    let edges: Vec<_> = t.edges().collect();
    let n = edges.len();
    for i in 0..n {
        for j in i + 1..n {
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            let (a, b) = edges[i];
            let (c, d) = edges[j];
            if adjacent {
                // Adjacent edges share a vertex; they must not fold back over each other.
                let (p, q, r) = if j == i + 1 { (a, b, d) } else { (c, d, b) };
                let x = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
                let back = (q[0] - p[0]) * (r[0] - q[0]) + (q[1] - p[1]) * (r[1] - q[1]);
                if x == 0.0 && back < 0.0 {
                    return Some(format!(
                        "edges {} and {} fold back over each other",
                        i + 1,
                        j + 1
                    ));
                }
            } else if segments_meet(a, b, c, d) {
                return Some(format!("edges {} and {} cross", i + 1, j + 1));
            }
        }
    }
    None
}

fn loops_meet(a: &TrimLoop, b: &TrimLoop) -> bool {
    a.edges()
        .any(|(p, q)| b.edges().any(|(r, s)| segments_meet(p, q, r, s)))
}

/// Parses a `.bpt` file (classic or extended); `name` prefixes the errors.
pub fn parse(text: &str, name: &str) -> Result<PatchModel, String> {
    let mut tokens = Tokens::new(text, name);
    let (count, count_line) = tokens.count("the patch count")?;
    if count == 0 {
        return Err(tokens.error_at(count_line, "the patch count is 0"));
    }
    let mut patches = Vec::with_capacity(count.min(1 << 16));
    for k in 0..count {
        let which = format!("patch {} of {count}", k + 1);
        let (du, line) = tokens.count(&format!("{which}: degree 'u'"))?;
        let (dv, _) = tokens.count(&format!("{which}: degree 'v'"))?;
        if (du, dv) != (3, 3) {
            return Err(tokens.error_at(
                line,
                format!("{which}: degrees {du} {dv}; only bicubic patches (3 3) are supported"),
            ));
        }
        let mut points = [[0.0; 3]; 16];
        for (n, p) in points.iter_mut().enumerate() {
            for (c, axis) in p.iter_mut().zip(["x", "y", "z"]) {
                *c = tokens
                    .number(&format!("{which}: control point {} {axis}", n + 1))?
                    .0;
            }
        }
        let mut patch = Patch::polynomial(points);
        let mut weighted = false;
        while let Some(t) = tokens.peek() {
            let line = t.line;
            match t.text {
                "weights" => {
                    tokens.next += 1;
                    if weighted {
                        return Err(tokens.error_at(line, format!("{which}: a second 'weights'")));
                    }
                    weighted = true;
                    for n in 0..16 {
                        let (w, wl) = tokens.number(&format!("{which}: weight {}", n + 1))?;
                        if w <= 0.0 {
                            return Err(tokens.error_at(
                                wl,
                                format!(
                                    "{which}: weight {} is {w}; weights must be positive",
                                    n + 1
                                ),
                            ));
                        }
                        patch.weights[n] = w;
                    }
                }
                "trim" => {
                    tokens.next += 1;
                    let (n, _) = tokens.count(&format!("{which}: trim point count"))?;
                    if n < 3 {
                        return Err(tokens.error_at(
                            line,
                            format!("{which}: a trim loop needs at least 3 points, got {n}"),
                        ));
                    }
                    let mut points = Vec::with_capacity(n.min(1 << 16));
                    for m in 0..n {
                        let (u, ul) = tokens.number(&format!("{which}: trim point {} u", m + 1))?;
                        let (v, _) = tokens.number(&format!("{which}: trim point {} v", m + 1))?;
                        if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
                            return Err(tokens.error_at(
                                ul,
                                format!(
                                    "{which}: trim point {} ({u}, {v}) is outside [0, 1]²",
                                    m + 1
                                ),
                            ));
                        }
                        points.push([u, v]);
                    }
                    let trim = TrimLoop { points };
                    if let Some(why) = self_crossing(&trim) {
                        return Err(tokens.error_at(line, format!("{which}: trim loop {why}")));
                    }
                    if patch.trims.iter().any(|other| loops_meet(other, &trim)) {
                        return Err(tokens.error_at(
                            line,
                            format!("{which}: trim loop crosses an earlier loop of the patch"),
                        ));
                    }
                    patch.trims.push(trim);
                }
                _ => break,
            }
        }
        patches.push(patch);
    }
    if let Some(t) = tokens.peek() {
        return Err(tokens.error_at(
            t.line,
            format!("'{}' after the {count} patches the count announced", t.text),
        ));
    }
    Ok(PatchModel { patches })
}

/// Reads and parses a `.bpt` file.
pub fn load(path: &std::path::Path) -> Result<PatchModel, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    parse(&text, &path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(header: &str, extra: &str) -> String {
        let mut s = format!("{header}\n3 3\n");
        for i in 0..4 {
            for j in 0..4 {
                s += &format!("{i} {j} {}\n", (i * j) as f64 * 0.1);
            }
        }
        s + extra
    }

    #[test]
    fn classic_and_extended() {
        let m = parse(&grid("1", ""), "t").unwrap();
        assert_eq!(m.patches.len(), 1);
        assert!(m.patches[0].is_polynomial() && m.patches[0].trims.is_empty());
        assert_eq!(m.patches[0].points[7], [1.0, 3.0, 0.30000000000000004]);
        let weights = "weights 1 2 1 1  1 1 1 1  1 1 1 1  1 1 1 0.5 # rational\n";
        let m = parse(
            &grid("1", &format!("{weights}trim 3 0.2 0.2 0.6 0.2 0.4 0.5\n")),
            "t",
        )
        .unwrap();
        assert_eq!(m.patches[0].weights[1], 2.0);
        assert_eq!(m.patches[0].weights[15], 0.5);
        assert_eq!(m.patches[0].trims[0].points.len(), 3);
        // Line breaks do not matter in the classic part.
        let flat = grid("1", "").replace('\n', " ");
        assert_eq!(parse(&flat, "t").unwrap().patches.len(), 1);
    }

    #[test]
    fn errors_are_one_line_and_name_the_line() {
        let two = grid("2", "");
        let cases = [
            (
                two.as_str().to_owned(),
                "t:18: file ends where patch 2 of 2: degree 'u' was expected",
            ),
            (
                grid("1", "3 3\n"),
                "t:19: '3' after the 1 patches the count announced",
            ),
            (
                grid("1", "").replace("3 3\n", "3 2\n"),
                "t:2: patch 1 of 1: degrees 3 2",
            ),
            (
                grid("1", "").replace("2 1 0.2", "2 1 NaN"),
                "t:12: patch 1 of 1: control point 10 z: 'NaN'",
            ),
            (
                grid("x", ""),
                "t:1: the patch count: 'x' is not a whole number",
            ),
            (grid("0", ""), "t:1: the patch count is 0"),
            (
                grid("1", "weights 1 1 1 1 1 1 1 1 1 1\n1 1 1 0 1 1\n"),
                "t:20: patch 1 of 1: weight 14 is 0; weights must be positive",
            ),
            (
                grid("1", "trim 4 0.2 0.2 0.8 0.8 0.8 0.2 0.2 0.8\n"),
                "t:19: patch 1 of 1: trim loop edges 1 and 3 cross",
            ),
            (
                grid(
                    "1",
                    "trim 3 0.2 0.2 0.8 0.2 0.5 0.6\ntrim 3 0.5 0.1 0.6 0.5 0.4 0.5\n",
                ),
                "t:20: patch 1 of 1: trim loop crosses an earlier loop",
            ),
            (
                grid("1", "trim 2 0.2 0.2 0.8 0.8\n"),
                "t:19: patch 1 of 1: a trim loop needs at least 3 points",
            ),
            (
                grid("1", "trim 3 0.2 0.2 1.5 0.2 0.5 0.6\n"),
                "t:19: patch 1 of 1: trim point 2 (1.5, 0.2) is outside",
            ),
            (
                grid("1", "trim 3 0.2 0.2 0.8 0.2 0.5 0.2\n"),
                "t:19: patch 1 of 1: trim loop edges 1 and 2 fold back",
            ),
        ];
        for (text, want) in cases {
            let e = parse(&text, "t").unwrap_err();
            assert!(e.starts_with(want) && !e.contains('\n'), "{e}\nwant {want}");
        }
    }
}
