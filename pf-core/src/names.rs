//! Enums chosen by name in configs and on the command line.

/// The member of `all` called `s` by `name`, or the one-line error a command line prints:
/// `unknown {what} '{s}' (expected a, b or c)`, listing every name, so the message cannot
/// fall behind the enum.
///
/// # Errors
/// `s` is no member's name.
pub fn parse_name<T: Copy>(
    what: &str,
    all: &[T],
    name: impl Fn(T) -> &'static str,
    s: &str,
) -> Result<T, String> {
    all.iter().copied().find(|&v| name(v) == s).ok_or_else(|| {
        let names: Vec<&str> = all.iter().map(|&v| name(v)).collect();
        let expected = match names.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => names.concat(),
        };
        format!("unknown {what} '{s}' (expected {expected})")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_name_and_lists_them_all_otherwise() {
        let all = [1u8, 2, 3];
        let name = |v: u8| ["", "one", "two", "three"][v as usize];
        assert_eq!(parse_name("digit", &all, name, "two"), Ok(2));
        assert_eq!(
            parse_name("digit", &all, name, "four"),
            Err("unknown digit 'four' (expected one, two or three)".to_string())
        );
        assert_eq!(
            parse_name("digit", &all[..1], name, "x"),
            Err("unknown digit 'x' (expected one)".to_string())
        );
    }
}
