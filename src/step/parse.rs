//! ISO 10303-21 (the STEP file format) → a table of entity instances, untyped.
//!
//! Only the DATA section is read; the HEADER is skipped. Every instance `#id = NAME(params);` or
//! complex `#id = (A(..) B(..));` becomes an [`Entity`]; parameters keep their kind (integer,
//! real, string, enumeration, reference, list, `$`, `*`, typed value such as
//! `LENGTH_MEASURE(25.4)`). Comments `/* */` are skipped. Strings keep `''` undoubled; the
//! `\X\`-style encodings are left as they are (names are only shown to the user).
//!
//! Errors carry the line and, once the `#id =` of an instance has been read, that id.

use super::StepError;
use std::collections::BTreeMap;

/// One parameter value.
#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    Int(i64),
    Real(f64),
    Str(String),
    /// `.NAME.` (booleans are `.T.` / `.F.`).
    Enum(String),
    Ref(u64),
    List(Vec<Param>),
    /// `$`: not given.
    Null,
    /// `*`: derived.
    Derived,
    /// `NAME(value)`, e.g. `LENGTH_MEASURE(25.4)`.
    Typed(String, Box<Param>),
}

/// One record `NAME(params)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    pub name: String,
    pub params: Vec<Param>,
}

/// An entity instance: one record, or several for a complex instance.
#[derive(Clone, Debug, PartialEq)]
pub struct Entity {
    pub records: Vec<Record>,
    /// 1-based line of the `#id`.
    pub line: usize,
}

impl Entity {
    /// The record called `name` (the only one of a simple instance).
    pub fn record(&self, name: &str) -> Option<&Record> {
        self.records.iter().find(|r| r.name == name)
    }

    /// The name of a simple instance, or the first record's.
    pub fn name(&self) -> &str {
        &self.records[0].name
    }
}

/// The DATA section: instances by id.
pub type Table = BTreeMap<u64, Entity>;

struct Lexer<'a> {
    s: &'a [u8],
    i: usize,
    line: usize,
    /// The instance being read, for errors.
    id: Option<u64>,
}

/// Nesting depth above which a parameter list is refused (keeps recursion bounded).
const MAX_DEPTH: usize = 64;

/// Parses the whole file into its instance table.
pub fn parse(bytes: &[u8]) -> Result<Table, StepError> {
    let mut lx = Lexer { s: bytes, i: 0, line: 1, id: None };
    lx.skip_ws()?;
    if !lx.eat_keyword("ISO-10303-21") {
        return Err(StepError::NotStep);
    }
    // Find `DATA;` (the header is skipped: nothing in it is needed).
    loop {
        lx.skip_ws()?;
        if lx.i >= lx.s.len() {
            return Err(lx.err_truncated("no DATA section"));
        }
        if lx.peek() == Some(b'\'') {
            lx.string()?;
            continue;
        }
        if lx.eat_keyword("DATA") {
            lx.skip_ws()?;
            // AP242 allows DATA('name', (...)); skip the parameters.
            if lx.peek() == Some(b'(') {
                lx.params(0)?;
                lx.skip_ws()?;
            }
            lx.expect(b';')?;
            break;
        }
        lx.i += 1;
    }
    let mut table = Table::new();
    loop {
        lx.skip_ws()?;
        lx.id = None;
        if lx.eat_keyword("ENDSEC") {
            lx.skip_ws()?;
            lx.expect(b';')?;
            return Ok(table);
        }
        if lx.i >= lx.s.len() {
            return Err(lx.err_truncated("the DATA section does not end (no ENDSEC)"));
        }
        let line = lx.line;
        lx.expect(b'#')?;
        let id = lx.unsigned()?;
        lx.id = Some(id);
        lx.skip_ws()?;
        lx.expect(b'=')?;
        lx.skip_ws()?;
        let records = if lx.peek() == Some(b'(') {
            lx.i += 1;
            let mut records = Vec::new();
            loop {
                lx.skip_ws()?;
                if lx.peek() == Some(b')') {
                    lx.i += 1;
                    break;
                }
                records.push(lx.record()?);
            }
            if records.is_empty() {
                return Err(lx.err("an empty complex instance"));
            }
            records
        } else {
            vec![lx.record()?]
        };
        lx.skip_ws()?;
        lx.expect(b';')?;
        if table.insert(id, Entity { records, line }).is_some() {
            return Err(StepError::Syntax { id: Some(id), line, message: "the id is defined twice".into() });
        }
    }
}

impl Lexer<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    fn err(&self, message: &str) -> StepError {
        StepError::Syntax { id: self.id, line: self.line, message: message.into() }
    }

    fn err_truncated(&self, message: &str) -> StepError {
        StepError::Truncated { id: self.id, line: self.line, message: message.into() }
    }

    fn skip_ws(&mut self) -> Result<(), StepError> {
        while let Some(c) = self.peek() {
            match c {
                b'\n' => {
                    self.line += 1;
                    self.i += 1;
                }
                b' ' | b'\t' | b'\r' => self.i += 1,
                b'/' if self.s.get(self.i + 1) == Some(&b'*') => {
                    self.i += 2;
                    loop {
                        match self.peek() {
                            None => return Err(self.err_truncated("a comment does not end")),
                            Some(b'*') if self.s.get(self.i + 1) == Some(&b'/') => {
                                self.i += 2;
                                break;
                            }
                            Some(c) => {
                                self.line += usize::from(c == b'\n');
                                self.i += 1;
                            }
                        }
                    }
                }
                _ => break,
            }
        }
        Ok(())
    }

    fn eat_keyword(&mut self, k: &str) -> bool {
        let end = self.i + k.len();
        let matches = self.s.get(self.i..end).is_some_and(|w| w.eq_ignore_ascii_case(k.as_bytes()))
            && !self.s.get(end).is_some_and(|&c| c.is_ascii_alphanumeric() || c == b'_');
        if matches {
            self.i = end;
        }
        matches
    }

    fn expect(&mut self, c: u8) -> Result<(), StepError> {
        match self.peek() {
            Some(x) if x == c => {
                self.i += 1;
                Ok(())
            }
            Some(x) => Err(self.err(&format!("expected `{}`, found `{}`", c as char, x as char))),
            None => Err(self.err_truncated(&format!("the file ends where `{}` was expected", c as char))),
        }
    }

    fn unsigned(&mut self) -> Result<u64, StepError> {
        let start = self.i;
        while self.peek().is_some_and(|c| c.is_ascii_digit()) {
            self.i += 1;
        }
        std::str::from_utf8(&self.s[start..self.i]).ok().and_then(|t| t.parse().ok()).ok_or_else(|| {
            if self.i >= self.s.len() {
                self.err_truncated("the file ends in an id")
            } else {
                self.err("expected an id number")
            }
        })
    }

    fn keyword(&mut self) -> Result<String, StepError> {
        let start = self.i;
        while self.peek().is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_' || c == b'-') {
            self.i += 1;
        }
        if start == self.i {
            return Err(match self.peek() {
                None => self.err_truncated("the file ends where an entity name was expected"),
                Some(c) => self.err(&format!("expected an entity name, found `{}`", c as char)),
            });
        }
        Ok(String::from_utf8_lossy(&self.s[start..self.i]).to_ascii_uppercase())
    }

    fn record(&mut self) -> Result<Record, StepError> {
        let name = self.keyword()?;
        self.skip_ws()?;
        let params = self.params(0)?;
        Ok(Record { name, params })
    }

    /// `( p, p, … )`
    fn params(&mut self, depth: usize) -> Result<Vec<Param>, StepError> {
        if depth > MAX_DEPTH {
            return Err(self.err("lists nested too deeply"));
        }
        self.expect(b'(')?;
        let mut out = Vec::new();
        self.skip_ws()?;
        if self.peek() == Some(b')') {
            self.i += 1;
            return Ok(out);
        }
        loop {
            self.skip_ws()?;
            out.push(self.param(depth)?);
            self.skip_ws()?;
            match self.peek() {
                Some(b',') => self.i += 1,
                Some(b')') => {
                    self.i += 1;
                    return Ok(out);
                }
                Some(c) => return Err(self.err(&format!("expected `,` or `)` in a list, found `{}`", c as char))),
                None => return Err(self.err_truncated("the file ends inside a parameter list")),
            }
        }
    }

    fn param(&mut self, depth: usize) -> Result<Param, StepError> {
        match self.peek() {
            None => Err(self.err_truncated("the file ends where a parameter was expected")),
            Some(b'$') => {
                self.i += 1;
                Ok(Param::Null)
            }
            Some(b'*') => {
                self.i += 1;
                Ok(Param::Derived)
            }
            Some(b'#') => {
                self.i += 1;
                Ok(Param::Ref(self.unsigned()?))
            }
            Some(b'\'') => Ok(Param::Str(self.string()?)),
            Some(b'"') => {
                // Binary: kept as a string of hex digits.
                self.i += 1;
                let start = self.i;
                while self.peek().is_some_and(|c| c != b'"') {
                    self.i += 1;
                }
                let text = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                self.expect(b'"')?;
                Ok(Param::Str(text))
            }
            Some(b'.') => {
                self.i += 1;
                let name = self.keyword()?;
                self.expect(b'.')?;
                Ok(Param::Enum(name))
            }
            Some(b'(') => Ok(Param::List(self.params(depth + 1)?)),
            Some(c) if c == b'-' || c == b'+' || c.is_ascii_digit() => self.number(),
            Some(c) if c.is_ascii_alphabetic() => {
                let name = self.keyword()?;
                self.skip_ws()?;
                let mut inner = self.params(depth + 1)?;
                if inner.len() != 1 {
                    return Err(self.err(&format!("typed parameter {name} must hold one value")));
                }
                Ok(Param::Typed(name, Box::new(inner.remove(0))))
            }
            Some(c) => Err(self.err(&format!("unexpected `{}` where a parameter was expected", c as char))),
        }
    }

    fn number(&mut self) -> Result<Param, StepError> {
        let start = self.i;
        let mut real = false;
        while let Some(c) = self.peek() {
            match c {
                b'0'..=b'9' | b'+' | b'-' => {}
                b'.' | b'e' | b'E' => real = true,
                _ => break,
            }
            self.i += 1;
        }
        let text = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
        let bad = || self.err(&format!("`{text}` is not a number"));
        if real {
            // STEP allows `1.` and `1.E2`; Rust's parser takes both.
            let v: f64 = text.parse().map_err(|_| bad())?;
            if !v.is_finite() {
                return Err(bad());
            }
            Ok(Param::Real(v))
        } else {
            Ok(Param::Int(text.parse().map_err(|_| bad())?))
        }
    }

    /// `'…'` with `''` for a quote.
    fn string(&mut self) -> Result<String, StepError> {
        self.expect(b'\'')?;
        let mut out = Vec::new();
        loop {
            match self.peek() {
                None => return Err(self.err_truncated("a string does not end")),
                Some(b'\'') if self.s.get(self.i + 1) == Some(&b'\'') => {
                    out.push(b'\'');
                    self.i += 2;
                }
                Some(b'\'') => {
                    self.i += 1;
                    return Ok(String::from_utf8_lossy(&out).into_owned());
                }
                Some(c) => {
                    self.line += usize::from(c == b'\n');
                    out.push(c);
                    self.i += 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "ISO-10303-21;\nHEADER;\nFILE_NAME('a;b','',(''),(''),'','','');\nENDSEC;\nDATA;\n\
        #1 = CARTESIAN_POINT('it''s', (0., 1.5E1, -2));\n/* c */#2=(LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.));\n\
        #3 = LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4), #2);\nENDSEC;\nEND-ISO-10303-21;\n";

    #[test]
    fn reads_simple_complex_and_typed_instances() {
        let t = parse(SMALL.as_bytes()).unwrap();
        assert_eq!(t.len(), 3);
        let p = t[&1].record("CARTESIAN_POINT").unwrap();
        assert_eq!(p.params[0], Param::Str("it's".into()));
        assert_eq!(p.params[1], Param::List(vec![Param::Real(0.0), Param::Real(15.0), Param::Int(-2)]));
        assert_eq!(t[&2].records.len(), 3);
        assert_eq!(t[&2].record("SI_UNIT").unwrap().params[0], Param::Enum("MILLI".into()));
        assert_eq!(t[&3].records[0].params[0], Param::Typed("LENGTH_MEASURE".into(), Box::new(Param::Real(25.4))));
        assert_eq!(t[&3].line, 8);
    }

    #[test]
    fn every_truncation_is_a_typed_error() {
        for cut in 0..SMALL.len() - 20 {
            match parse(&SMALL.as_bytes()[..cut]) {
                Err(StepError::NotStep | StepError::Truncated { .. } | StepError::Syntax { .. }) => {}
                other => panic!("cut at {cut}: {other:?}"),
            }
        }
    }

    #[test]
    fn a_garbled_instance_names_its_id() {
        let bad = SMALL.replace("(0., 1.5E1, -2)", "(0., 1.5E1 -2 ?)");
        match parse(bad.as_bytes()) {
            Err(StepError::Syntax { id: Some(1), line: 6, .. }) => {}
            other => panic!("{other:?}"),
        }
    }
}
