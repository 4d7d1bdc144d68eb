//! Wavefront MTL material libraries, read by our own parser.
//!
//! Why not `tobj`'s: tobj 4.0.5 panics on the valid one-value colour form (`Kd 0.5`: its
//! `parse_float3` unwraps a conversion to three numbers) and its errors carry no line.
//! This parser cannot panic, and it keeps every statement's key, raw values and 1-based
//! line, so that whatever reads a value later can report `file.mtl:LINE`. It checks the
//! statements whose syntax the format fixes:
//! * `Ka`, `Kd`, `Ks`, `Ke`, `Tf`: one number (a grey: g and b default to r) or three;
//! * `Ns`, `Ni`, `d`, `Tr`: one number (`Tr` is transparency, 1 − `d`);
//! * `illum`: an integer 0–10;
//! * `newmtl`: a name (the rest of the line, as `tobj` matches `usemtl` names).
//!
//! Every other statement (texture maps, our `bsdf`, the thesis's `rough`, `nu`, … ) is
//! kept as raw text for whoever reads it. Numbers must be finite. A token that starts
//! with `#` begins a comment; statements before the first `newmtl` belong to no material
//! and are checked, then dropped. Where a key repeats, the last statement counts.

/// One statement of a material: `key values…` on line `line`.
#[derive(Clone, Debug, PartialEq)]
pub struct Statement {
    /// The keyword (`Kd`, `illum`, `bsdf`, …), case-sensitive as in the format.
    pub key: String,
    /// Everything after the keyword, trimmed, comment removed, not interpreted.
    pub values: String,
    /// The 1-based line, for messages.
    pub line: usize,
}

/// The texture statements of the format (checked for syntax; the renderer applies
/// `map_Kd`, `map_Ks`, `map_d`, `norm`/`map_Kn` and `bump`/`map_bump`).
pub const TEXTURE_KEYS: &[&str] = &[
    "map_Ka", "map_Kd", "map_Ks", "map_Ke", "map_Ns", "map_d", "map_bump", "bump", "norm", "map_Kn", "disp", "decal",
    "refl",
];

/// A texture statement's file and options (see [`Statement::texture`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureStatement {
    /// The image file, relative to the MTL file.
    pub file: String,
    /// `-o u v w`: added to the texture coordinates (OBJ's, v upwards).
    pub offset: [f32; 3],
    /// `-s u v w`: multiplies the texture coordinates.
    pub scale: [f32; 3],
    /// `-clamp on`: clamp instead of tiling.
    pub clamp: bool,
    /// `-bm`: the bump multiplier.
    pub bump: f32,
}

/// A malformed statement: where and why (the caller knows the file).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MtlError {
    /// The 1-based line.
    pub line: usize,
    /// What is wrong, naming the statement.
    pub message: String,
}

/// A statement's numbers: one, or three.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Numbers {
    /// One number.
    One(f32),
    /// Three numbers.
    Three([f32; 3]),
}

impl Statement {
    fn error(&self, message: String) -> MtlError {
        MtlError { line: self.line, message }
    }

    /// The first three numbers and how many tokens there are in all, or why a token is
    /// not a finite number. Reads at most four tokens past the count it needs, so a huge
    /// line costs no allocation.
    fn numbers(&self) -> Result<(usize, [f32; 3]), MtlError> {
        let mut first = [0.0f32; 3];
        let mut count = 0;
        for tok in self.values.split_whitespace() {
            let v: f32 =
                tok.parse().map_err(|_| self.error(format!("{}: '{}' is not a number", self.key, quote(tok))))?;
            if !v.is_finite() {
                return Err(self.error(format!("{}: '{}' is not finite", self.key, quote(tok))));
            }
            if count < 3 {
                first[count] = v;
            }
            count += 1;
        }
        Ok((count, first))
    }

    /// One number or three (`Rs 0.1`, `Rd 0.4 0.4 0.4`): how the extension statements
    /// give scalars and colours.
    pub fn one_or_three(&self) -> Result<Numbers, MtlError> {
        match self.numbers()? {
            (1, [v, ..]) => Ok(Numbers::One(v)),
            (3, rgb) => Ok(Numbers::Three(rgb)),
            (n, _) => Err(self.error(format!("{} needs 1 or 3 numbers, got {n}", self.key))),
        }
    }

    /// A colour statement (`Kd r [g b]`): one value is a grey, as the format says.
    pub fn colour(&self) -> Result<[f32; 3], MtlError> {
        Ok(match self.one_or_three()? {
            Numbers::One(v) => [v; 3],
            Numbers::Three(rgb) => rgb,
        })
    }

    /// A one-number statement (`Ns`, `Ni`, `d`, `Tr`).
    pub fn scalar(&self) -> Result<f32, MtlError> {
        match self.numbers()? {
            (1, [v, ..]) => Ok(v),
            (n, _) => Err(self.error(format!("{} needs 1 number, got {n}", self.key))),
        }
    }

    /// A texture statement (`map_Kd [-options] file`): its file and the options we use
    /// (`-o`, `-s`, `-clamp`, `-bm`); the other options of the format are skipped with
    /// their arguments. The file is the rest of the line (it may contain spaces); the last
    /// word is always part of it, even if it starts with a minus sign.
    pub fn texture(&self) -> Result<TextureStatement, MtlError> {
        let mut t =
            TextureStatement { file: String::new(), offset: [0.0; 3], scale: [1.0; 3], clamp: false, bump: 1.0 };
        let toks: Vec<&str> = self.values.split_whitespace().collect();
        let mut i = 0;
        let number = |tok: Option<&&str>| tok.and_then(|t| t.parse::<f32>().ok()).filter(|v| v.is_finite());
        while i + 1 < toks.len() && toks[i].starts_with('-') && toks[i].len() > 1 && number(Some(&toks[i])).is_none() {
            let option = toks[i];
            i += 1;
            let mut values = Vec::new();
            let (least, most) = match option {
                "-o" | "-s" | "-t" => (1, 3),
                "-mm" => (2, 2),
                "-bm" | "-boost" | "-texres" => (1, 1),
                "-blendu" | "-blendv" | "-cc" | "-clamp" | "-imfchan" | "-type" => {
                    let Some(word) = toks.get(i) else {
                        return Err(self.error(format!("{}: {option} needs a value", self.key)));
                    };
                    if option == "-clamp" {
                        t.clamp = match *word {
                            "on" => true,
                            "off" => false,
                            other => {
                                return Err(self.error(format!(
                                    "{}: -clamp '{}' is not on or off",
                                    self.key,
                                    quote(other)
                                )));
                            }
                        };
                    }
                    i += 1;
                    continue;
                }
                other => return Err(self.error(format!("{}: unknown option '{}'", self.key, quote(other)))),
            };
            while values.len() < most
                && let Some(v) = number(toks.get(i))
            {
                values.push(v);
                i += 1;
            }
            if values.len() < least {
                return Err(self.error(format!("{}: {option} needs {least} number(s)", self.key)));
            }
            match option {
                "-o" => t.offset[..values.len()].copy_from_slice(&values),
                "-s" => t.scale[..values.len()].copy_from_slice(&values),
                "-bm" => t.bump = values[0],
                _ => {}
            }
        }
        t.file = toks[i.min(toks.len())..].join(" ");
        if t.file.is_empty() {
            return Err(self.error(format!("{} names no file", self.key)));
        }
        Ok(t)
    }

    /// An `illum` statement: the illumination model, 0–10.
    pub fn illum(&self) -> Result<u8, MtlError> {
        let mut toks = self.values.split_whitespace();
        match (toks.next().map(str::parse::<u8>), toks.next()) {
            (Some(Ok(v)), None) if v <= 10 => Ok(v),
            _ => Err(self.error(format!("illum: '{}' is not a model number 0–10", quote(&self.values)))),
        }
    }

    /// Checks the syntax of the statements the format fixes (see the module doc).
    fn check(&self) -> Result<(), MtlError> {
        match self.key.as_str() {
            "Ka" | "Kd" | "Ks" | "Ke" | "Tf" => self.colour().map(drop),
            "Ns" | "Ni" | "d" | "Tr" => self.scalar().map(drop),
            "illum" => self.illum().map(drop),
            key if TEXTURE_KEYS.contains(&key) => self.texture().map(drop),
            _ => Ok(()),
        }
    }
}

/// A material: its name, the line of its `newmtl`, and its statements in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlMaterial {
    /// The name `usemtl` refers to.
    pub name: String,
    /// The 1-based line of its `newmtl` (0 for materials made in code).
    pub line: usize,
    /// Its statements, in file order.
    pub statements: Vec<Statement>,
}

impl MtlMaterial {
    /// The statement that sets `key`: the last one, as in other MTL readers.
    pub fn get(&self, key: &str) -> Option<&Statement> {
        self.statements.iter().rev().find(|s| s.key == key)
    }

    /// True if any statement sets `key`.
    pub fn has(&self, key: &str) -> bool {
        self.get(key).is_some()
    }

    /// The opacity: `d`, else 1 − `Tr` (`d` wins where both are given, as in
    /// tinyobjloader, since exporters disagree about `Tr`).
    pub fn dissolve(&self) -> Result<Option<f32>, MtlError> {
        if let Some(d) = self.get("d") {
            return d.scalar().map(Some);
        }
        self.get("Tr").map(|tr| tr.scalar().map(|t| 1.0 - t)).transpose()
    }
}

/// Parses an MTL library: its materials in file order, or its first malformed statement.
pub fn parse_mtl(text: &str) -> Result<Vec<MtlMaterial>, MtlError> {
    let mut materials: Vec<MtlMaterial> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let trimmed = raw.trim();
        let (key, rest) = trimmed.split_once(char::is_whitespace).unwrap_or((trimmed, ""));
        if key.is_empty() || key.starts_with('#') {
            continue;
        }
        if key == "newmtl" {
            let name = rest.trim();
            if name.is_empty() {
                return Err(MtlError { line, message: "newmtl needs a material name".into() });
            }
            materials.push(MtlMaterial { name: name.into(), line, statements: Vec::new() });
            continue;
        }
        let statement = Statement { key: key.into(), values: strip_comment(rest).into(), line };
        statement.check()?;
        // Statements before the first `newmtl` are checked, then dropped.
        if let Some(m) = materials.last_mut() {
            m.statements.push(statement);
        }
    }
    Ok(materials)
}

/// `text` up to the first token that starts with `#`, trimmed.
fn strip_comment(text: &str) -> &str {
    let mut prev_space = true;
    for (i, c) in text.char_indices() {
        if c == '#' && prev_space {
            return text[..i].trim();
        }
        prev_space = c.is_whitespace();
    }
    text.trim()
}

/// A token for a message, cut to a readable length (a mutated file can put a megabyte on
/// one line).
pub(crate) fn quote(text: &str) -> std::borrow::Cow<'_, str> {
    shorten(text, 40)
}

/// `text` cut to at most `max` characters, with an ellipsis where it was cut.
pub(crate) fn shorten(text: &str, max: usize) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(max) {
        None => text.into(),
        Some((end, _)) => format!("{}…", &text[..end]).into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_materials_statements_and_lines() {
        let text =
            "# c\nKd 1 1 1\nnewmtl a b\n  Kd 0.5 # grey\nillum 2\nmap_Kd my#tex.png # c\nnewmtl c\nKs 0.1 0.2 0.3\n";
        let m = parse_mtl(text).unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!((m[0].name.as_str(), m[0].line), ("a b", 3));
        let kd = m[0].get("Kd").unwrap();
        assert_eq!((kd.values.as_str(), kd.line, kd.colour()), ("0.5", 4, Ok([0.5; 3])));
        assert_eq!(m[0].get("illum").unwrap().illum(), Ok(2));
        assert_eq!(m[0].get("map_Kd").unwrap().values, "my#tex.png");
        assert_eq!(m[1].get("Ks").unwrap().colour(), Ok([0.1, 0.2, 0.3]));
        assert!(m[1].get("Kd").is_none());
    }

    #[test]
    fn texture_statements_give_their_file_and_options() {
        let st = |values: &str| Statement { key: "map_Kd".into(), values: values.into(), line: 7 };
        let t = st("-s 2 3 -o 0.5 -clamp on -bm 0.25 -blendu off -mm 0 1 -imfchan r my tex.png").texture().unwrap();
        assert_eq!(t.file, "my tex.png");
        assert_eq!((t.scale, t.offset, t.clamp, t.bump), ([2.0, 3.0, 1.0], [0.5, 0.0, 0.0], true, 0.25));
        let plain = st("brick.jpg").texture().unwrap();
        assert_eq!((plain.file.as_str(), plain.scale, plain.clamp, plain.bump), ("brick.jpg", [1.0; 3], false, 1.0));
        // A file name that starts with a minus sign and a number is still a file.
        assert_eq!(st("-o 1 -2.png").texture().unwrap().file, "-2.png");
        for (bad, needle) in [
            ("", "names no file"),
            ("-s 2", "names no file"),
            ("-clamp maybe x.png", "-clamp 'maybe'"),
            ("-bm x.png", "-bm needs 1"),
            ("-frobnicate 3 x.png", "unknown option '-frobnicate'"),
        ] {
            let e = st(bad).texture().unwrap_err();
            assert!(e.message.contains(needle) && e.line == 7, "{bad}: {e:?}");
        }
        // Texture statements are checked when the library is read.
        let e = parse_mtl("newmtl a\nmap_Kd -bm x y\n").unwrap_err();
        assert_eq!(e.line, 2, "{e:?}");
    }

    #[test]
    fn one_value_colours_are_grey_and_other_counts_are_errors_with_their_line() {
        assert_eq!(parse_mtl("newmtl a\nKd 0.5\n").unwrap()[0].get("Kd").unwrap().colour(), Ok([0.5; 3]));
        for (text, needle) in [
            ("newmtl a\n\nKd 0.5 0.5\n", "Kd needs 1 or 3 numbers, got 2"),
            ("newmtl a\n\nKe 1 2 3 4\n", "Ke needs 1 or 3 numbers, got 4"),
            ("newmtl a\n\nTf\n", "Tf needs 1 or 3 numbers, got 0"),
            ("newmtl a\n\nKd 0.5 0.5 zz\n", "Kd: 'zz' is not a number"),
            ("newmtl a\n\nKs 1e39 0 0\n", "Ks: '1e39' is not finite"),
            ("newmtl a\n\nNs 1 2\n", "Ns needs 1 number, got 2"),
            ("newmtl a\n\nd nan\n", "d: 'nan' is not finite"),
            ("newmtl a\n\nillum 11\n", "illum: '11' is not a model number 0–10"),
            ("newmtl a\n\nillum -1\n", "not a model number"),
            ("newmtl a\n\nnewmtl\n", "newmtl needs a material name"),
        ] {
            let e = parse_mtl(text).unwrap_err();
            assert_eq!(e.line, 3, "{text:?}: {e:?}");
            assert!(e.message.contains(needle), "{text:?}: {}", e.message);
        }
    }

    #[test]
    fn dissolve_is_d_else_one_minus_tr() {
        let d = |text: &str| parse_mtl(text).unwrap()[0].dissolve().unwrap();
        assert_eq!(d("newmtl a\n"), None);
        assert_eq!(d("newmtl a\nTr 0.25\n"), Some(0.75));
        assert_eq!(d("newmtl a\nd 0.5\nTr 0.25\n"), Some(0.5));
        assert_eq!(d("newmtl a\nd 0.5\nd 0.25\n"), Some(0.25));
    }

    #[test]
    fn extension_values_are_one_or_three_numbers() {
        let m = &parse_mtl("newmtl a\nrough 0.2\nRs 0.1 0.2 0.3\nnu 1 2\nsigma x\n").unwrap()[0];
        assert_eq!(m.get("rough").unwrap().one_or_three(), Ok(Numbers::One(0.2)));
        assert_eq!(m.get("Rs").unwrap().one_or_three(), Ok(Numbers::Three([0.1, 0.2, 0.3])));
        let e = m.get("nu").unwrap().one_or_three().unwrap_err();
        assert_eq!((e.line, e.message.as_str()), (4, "nu needs 1 or 3 numbers, got 2"));
        assert_eq!(m.get("sigma").unwrap().one_or_three().unwrap_err().line, 5);
    }

    #[test]
    fn messages_quote_at_most_forty_characters() {
        let long = "x".repeat(1000);
        let e = parse_mtl(&format!("newmtl a\nKd {long}\n")).unwrap_err();
        assert!(e.message.len() < 80, "{}", e.message);
    }
}
