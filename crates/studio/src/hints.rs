//! Hints a model's comments give the studio: the box to view it in and the
//! default values and ranges of its `a[k]` parameters.
//!
//! - Box: the first `Box [lo, hi]^3` or `Box [x0, x1] x [y0, y1] x [z0, z1]`
//!   in the comments (case-insensitive, may span comment lines; `Suggested
//!   box` works too), as the example models write it.
//! - Parameters: a comment `a[K] = V` sets the default of `a[K]`, and
//!   `a[K] = V in [LO, HI]` also the slider's range.
//! - Data fields: `--field NAME=SOURCE` in a comment (the CLI's option, as
//!   `microfrep fill` writes it in its header) binds a mesh, scan or CSV
//!   file under the working directory as the function `NAME(x)`.

/// Text of all `--` comments, joined with spaces (a comment that starts
/// inside a line counts too).
fn comment_text(src: &str) -> String {
    let mut out = String::new();
    for line in src.lines() {
        if let Some(i) = line.find("--") {
            out.push_str(&line[i + 2..]);
            out.push(' ');
        }
    }
    out
}

/// A tiny cursor over comment text.
struct Cur<'a> {
    s: &'a [u8],
    i: usize,
}

impl Cur<'_> {
    fn ws(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }
    fn eat(&mut self, c: u8) -> Option<()> {
        self.ws();
        (self.s.get(self.i) == Some(&c)).then(|| self.i += 1)
    }
    fn number(&mut self) -> Option<f64> {
        self.ws();
        let start = self.i;
        while self.i < self.s.len()
            && (self.s[self.i].is_ascii_digit() || b"+-.eE".contains(&self.s[self.i]))
        {
            self.i += 1;
        }
        let v: f64 = std::str::from_utf8(&self.s[start..self.i])
            .ok()?
            .parse()
            .ok()?;
        v.is_finite().then_some(v)
    }
    /// `[a, b]` with a < b.
    fn range(&mut self) -> Option<[f64; 2]> {
        self.eat(b'[')?;
        let a = self.number()?;
        self.eat(b',')?;
        let b = self.number()?;
        self.eat(b']')?;
        (a < b).then_some([a, b])
    }
}

/// The box named in the comments, as `[min, max]`.
pub fn box_hint(src: &str) -> Option<[[f64; 3]; 2]> {
    let text = comment_text(src);
    let lower = text.to_ascii_lowercase();
    let mut from = 0;
    while let Some(k) = lower[from..].find("box") {
        let at = from + k + 3;
        from = at;
        let mut c = Cur {
            s: text.as_bytes(),
            i: at,
        };
        let Some(x) = c.range() else { continue };
        let save = c.i;
        if c.eat(b'^').is_some() && c.eat(b'3').is_some() {
            return Some([[x[0]; 3], [x[1]; 3]]);
        }
        c.i = save;
        let mut axes = vec![x];
        while axes.len() < 3 {
            if c.eat(b'x').is_none() {
                break;
            }
            match c.range() {
                Some(r) => axes.push(r),
                None => break,
            }
        }
        if axes.len() == 3 {
            return Some([
                [axes[0][0], axes[1][0], axes[2][0]],
                [axes[0][1], axes[1][1], axes[2][1]],
            ]);
        }
    }
    None
}

/// A parameter hint: `a[index]` (1-based) defaults to `value`, with an
/// optional slider range.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamHint {
    /// 1-based index `k` of `a[k]`.
    pub index: usize,
    /// Default value.
    pub value: f64,
    /// Slider range, if given.
    pub range: Option<[f64; 2]>,
}

/// The `a[K] = V [in [LO, HI]]` hints of the comments (K up to 4096),
/// first one per index.
pub fn param_hints(src: &str) -> Vec<ParamHint> {
    let text = comment_text(src);
    let b = text.as_bytes();
    let mut out: Vec<ParamHint> = Vec::new();
    let mut i = 0;
    while i + 1 < b.len() {
        let starts = (b[i] == b'a' || b[i] == b'A')
            && b[i + 1] == b'['
            && (i == 0 || !b[i - 1].is_ascii_alphanumeric());
        if !starts {
            i += 1;
            continue;
        }
        let mut c = Cur { s: b, i: i + 2 };
        i += 2;
        let Some(k) = c.number() else { continue };
        if k.fract() != 0.0 || !(1.0..=4096.0).contains(&k) || c.eat(b']').is_none() {
            continue;
        }
        if c.eat(b'=').is_none() {
            continue;
        }
        let Some(value) = c.number() else { continue };
        let save = c.i;
        c.ws();
        let range = if text[c.i..].starts_with("in") {
            c.i += 2;
            c.range()
        } else {
            None
        };
        if range.is_none() {
            c.i = save;
        }
        let index = k as usize;
        if !out.iter().any(|h| h.index == index) {
            out.push(ParamHint {
                index,
                value,
                range,
            });
        }
        i = c.i;
    }
    out
}

/// The `--field NAME=SOURCE` bindings of the comments, first one per name
/// (names compared case-insensitively, as HyperFun does). `SOURCE` runs to
/// the next white space, less a trailing `.`, `,`, `;` or `)`.
pub fn field_hints(src: &str) -> Vec<(String, String)> {
    let text = comment_text(src);
    let mut out: Vec<(String, String)> = Vec::new();
    let mut from = 0;
    while let Some(k) = text[from..].find("--field") {
        let mut i = from + k + "--field".len();
        from = i;
        let b = text.as_bytes();
        if i < b.len() && !b[i].is_ascii_whitespace() {
            continue;
        }
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        let name_at = i;
        while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
            i += 1;
        }
        let name = &text[name_at..i];
        if name.is_empty() || b[name_at].is_ascii_digit() || b.get(i) != Some(&b'=') {
            continue;
        }
        let spec_at = i + 1;
        let end = text[spec_at..]
            .find(|c: char| c.is_whitespace())
            .map_or(text.len(), |e| spec_at + e);
        let spec = text[spec_at..end].trim_end_matches(['.', ',', ';', ')']);
        from = end;
        if spec.is_empty() || out.iter().any(|(n, _)| n.eq_ignore_ascii_case(name)) {
            continue;
        }
        out.push((name.to_string(), spec.to_string()));
    }
    out
}

/// A slider range about `v`: from the hint, else `[v - |v|, v + |v|]`
/// (`[-1, 1]` about 0).
pub fn default_range(v: f64, hint: Option<[f64; 2]>) -> [f64; 2] {
    if let Some(r) = hint {
        return r;
    }
    if v == 0.0 {
        [-1.0, 1.0]
    } else {
        [v - v.abs(), v + v.abs()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_of_the_examples() {
        let cube = "-- the 10 x 10 x 10 tori-ball block. Box [-1, 1]^3.\nmy_model(x[3]) {}";
        assert_eq!(box_hint(cube), Some([[-1.0; 3], [1.0; 3]]));
        let spread = "-- shell. Box [-2.2, 2.2] x [-1.2, 1.2]\n-- x [-0.7, 1.7].\nm(x[3]){}";
        assert_eq!(
            box_hint(spread),
            Some([[-2.2, -1.2, -0.7], [2.2, 1.2, 1.7]])
        );
        let suggested = "-- cell on [-1, 1]^3. Suggested\n-- box [-2, 2]^3.";
        assert_eq!(box_hint(suggested), Some([[-2.0; 3], [2.0; 3]]));
        assert_eq!(box_hint("-- no box here\nbox = 1;"), None);
        assert_eq!(box_hint("-- Box [1, -1]^3"), None);
    }

    #[test]
    fn parameter_hints() {
        let src =
            "-- a[1] = 0.5 in [0.1, 2]\n-- a[2]=3; a[1] = 9\n-- data[1] = 4\nm(x[3], a[2]) {}";
        let h = param_hints(src);
        assert_eq!(
            h,
            vec![
                ParamHint {
                    index: 1,
                    value: 0.5,
                    range: Some([0.1, 2.0])
                },
                ParamHint {
                    index: 2,
                    value: 3.0,
                    range: None
                },
            ]
        );
        assert_eq!(default_range(0.5, None), [0.0, 1.0]);
        assert_eq!(default_range(-2.0, None), [-4.0, 0.0]);
        assert_eq!(default_range(0.0, None), [-1.0, 1.0]);
    }

    #[test]
    fn field_bindings() {
        // The header `microfrep fill` writes, and a second binding.
        let src = "-- Made by `microfrep fill`: gyroid.\n-- The part is a data field: load with --field part=parts/femur.stl:weld=0.01\n\
                   -- and --field Density=d.csv. Also --field part=other.stl, --fieldx a=b,\n\
                   -- --field 9a=x.stl --field bad x.stl\nmy_model(x[3], a[1]) { my_model = part(x); }\n\
                   -- --field tail=t.nrrd:iso=300";
        assert_eq!(
            field_hints(src),
            vec![
                ("part".into(), "parts/femur.stl:weld=0.01".into()),
                ("Density".into(), "d.csv".into()),
                ("tail".into(), "t.nrrd:iso=300".into()),
            ]
        );
        assert!(field_hints("my_model(x[3], a[1]) { my_model = part(x); }").is_empty());
    }
}
