//! SI unit strings as vanefit writes them (`m3/(s*Pa)`, `N*m*s2/rad2`) turned into FMI
//! unit definitions: a Modelica-style name (`m3/(s.Pa)`) and the exponents of the SI base
//! units that FMI's `<BaseUnit>` carries.

/// Exponents of kg, m, s and rad (FMI `BaseUnit` attributes `kg`, `m`, `s`, `rad`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BaseUnit {
    /// Exponent of the kilogram.
    pub kg: i32,
    /// Exponent of the metre.
    pub m: i32,
    /// Exponent of the second.
    pub s: i32,
    /// Exponent of the radian.
    pub rad: i32,
}

impl BaseUnit {
    fn scaled(self, k: i32) -> Self {
        Self {
            kg: self.kg * k,
            m: self.m * k,
            s: self.s * k,
            rad: self.rad * k,
        }
    }

    fn plus(self, o: Self) -> Self {
        Self {
            kg: self.kg + o.kg,
            m: self.m + o.m,
            s: self.s + o.s,
            rad: self.rad + o.rad,
        }
    }
}

/// The FMI (Modelica) spelling of a vanefit unit string: `*` becomes `.`; `None` for the
/// dimensionless `1`, which FMI writes as no unit at all.
pub fn fmi_name(unit: &str) -> Option<String> {
    let u = unit.trim();
    (!u.is_empty() && u != "1").then(|| u.replace('*', "."))
}

/// The base-unit exponents of a vanefit unit string: products (`*`), quotients (`/`),
/// parentheses and integer powers written after the symbol (`m3`, `s2`) of kg, m, s, rad,
/// Pa (kg·m⁻¹·s⁻²) and N (kg·m·s⁻²). `None` for a symbol outside these (the unit is then
/// declared by name only).
pub fn base_unit(unit: &str) -> Option<BaseUnit> {
    let tokens = tokenize(unit)?;
    let mut pos = 0;
    let b = product(&tokens, &mut pos)?;
    (pos == tokens.len()).then_some(b)
}

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Symbol(BaseUnit),
    Times,
    Over,
    Open,
    Close,
}

fn tokenize(unit: &str) -> Option<Vec<Token>> {
    let mut out = Vec::new();
    let chars: Vec<char> = unit.chars().filter(|c| !c.is_whitespace()).collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let simple = match c {
            '*' | '.' => Some(Token::Times),
            '/' => Some(Token::Over),
            '(' => Some(Token::Open),
            ')' => Some(Token::Close),
            _ => None,
        };
        if let Some(t) = simple {
            out.push(t);
            i += 1;
            continue;
        }
        let start = i;
        while i < chars.len() && chars[i].is_ascii_alphabetic() {
            i += 1;
        }
        let name: String = chars[start..i].iter().collect();
        let digits_start = i;
        while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '-') {
            i += 1;
        }
        let digits: String = chars[digits_start..i].iter().collect();
        if name.is_empty() && digits == "1" {
            out.push(Token::Symbol(BaseUnit::default()));
            continue;
        }
        let power: i32 = if digits.is_empty() {
            1
        } else {
            digits.parse().ok()?
        };
        out.push(Token::Symbol(symbol(&name)?.scaled(power)));
    }
    Some(out)
}

fn symbol(name: &str) -> Option<BaseUnit> {
    let b = |kg, m, s, rad| BaseUnit { kg, m, s, rad };
    Some(match name {
        "kg" => b(1, 0, 0, 0),
        "m" => b(0, 1, 0, 0),
        "s" => b(0, 0, 1, 0),
        "rad" => b(0, 0, 0, 1),
        "Pa" => b(1, -1, -2, 0),
        "N" => b(1, 1, -2, 0),
        _ => return None,
    })
}

/// factor (('*' | '/') factor)*, left to right.
fn product(tokens: &[Token], pos: &mut usize) -> Option<BaseUnit> {
    let mut acc = factor(tokens, pos)?;
    while let Some(op) = tokens.get(*pos) {
        let sign = match op {
            Token::Times => 1,
            Token::Over => -1,
            _ => break,
        };
        *pos += 1;
        acc = acc.plus(factor(tokens, pos)?.scaled(sign));
    }
    Some(acc)
}

fn factor(tokens: &[Token], pos: &mut usize) -> Option<BaseUnit> {
    match tokens.get(*pos)? {
        Token::Symbol(b) => {
            *pos += 1;
            Some(*b)
        }
        Token::Open => {
            *pos += 1;
            let inner = product(tokens, pos)?;
            (tokens.get(*pos) == Some(&Token::Close)).then(|| {
                *pos += 1;
                inner
            })
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(kg: i32, m: i32, s: i32, rad: i32) -> Option<BaseUnit> {
        Some(BaseUnit { kg, m, s, rad })
    }

    #[test]
    fn vanefit_units_reduce_to_si_base_units() {
        // m³/(s·Pa) = m³·s⁻¹·kg⁻¹·m·s² = kg⁻¹·m⁴·s.
        assert_eq!(base_unit("m3/(s*Pa)"), b(-1, 4, 1, 0));
        assert_eq!(base_unit("N*m"), b(1, 2, -2, 0));
        assert_eq!(base_unit("N*m*s/rad"), b(1, 2, -1, -1));
        assert_eq!(base_unit("N*m*s2/rad2"), b(1, 2, 0, -2));
        assert_eq!(base_unit("kg*m2"), b(1, 2, 0, 0));
        assert_eq!(base_unit("N*m/Pa"), b(0, 3, 0, 0));
        assert_eq!(base_unit("kg/s"), b(1, 0, -1, 0));
        assert_eq!(base_unit("rad/s"), b(0, 0, -1, 1));
        // Left to right inside the parentheses: s·Pa·rad/s = kg·m⁻¹·s⁻²·rad.
        assert_eq!(base_unit("kg/(s*Pa*rad/s)"), b(0, 1, 2, -1));
        assert_eq!(base_unit("1"), b(0, 0, 0, 0));
        assert_eq!(base_unit("K"), None);
        assert_eq!(base_unit("m3/(s"), None);
    }

    #[test]
    fn fmi_names_use_the_modelica_product_dot() {
        assert_eq!(fmi_name("m3/(s*Pa)").as_deref(), Some("m3/(s.Pa)"));
        assert_eq!(fmi_name("1"), None);
    }
}
