//! Mutations of mapc's inputs, shared by the mutation test (`tests/mutation.rs`, through the binary) and the
//! in-process fuzz harness (`examples/fuzz_readers.rs`): a seeded generator, hostile numbers, and the text and
//! byte mutations drawn from them.
#![allow(dead_code)]

/// splitmix64: a tiny generator whose stream is fixed by its seed on every platform.
pub struct Draw(pub u64);

impl Draw {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Numbers a careless or hostile file or flag holds.
pub const HOSTILE_NUMBERS: &[&str] = &[
    "-1",
    "0",
    "-0",
    "1e308",
    "-1e308",
    "1e-300",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "-9223372036854775808",
    "0.0000001",
    "999999999",
    "1e9",
    "",
    "abc",
    "0x10",
    "1,5",
    "\u{202e}7",
    "\u{1b}[2J",
];

/// One mutation of a text input: a number replaced by a hostile one, an attribute or line dropped, a line
/// doubled, or the text cut short.
pub fn mutate_text(text: &str, d: &mut Draw) -> (String, String) {
    let numbers: Vec<(usize, usize)> = number_spans(text);
    match d.below(6) {
        0..=2 if !numbers.is_empty() => {
            let (a, b) = *d.pick(&numbers);
            let with = *d.pick(HOSTILE_NUMBERS);
            let what = format!("number `{}` at byte {a} -> `{with}`", &text[a..b]);
            (format!("{}{}{}", &text[..a], with, &text[b..]), what)
        }
        3 => {
            let lines: Vec<&str> = text.lines().collect();
            let i = d.below(lines.len());
            let what = format!("line {} dropped", i + 1);
            let mut kept = lines.clone();
            kept.remove(i);
            (kept.join("\n"), what)
        }
        4 => {
            let lines: Vec<&str> = text.lines().collect();
            let i = d.below(lines.len());
            let what = format!("line {} doubled", i + 1);
            let mut out = lines.clone();
            out.insert(i, lines[i]);
            (out.join("\n"), what)
        }
        _ => {
            let mut cut = d.below(text.len());
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            (text[..cut].to_string(), format!("cut at byte {cut}"))
        }
    }
}

/// The byte spans of decimal numbers in `text`.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'))
        {
            let start = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.' || b[j] == b'e') {
                j += 1;
            }
            if j == b.len() || !(b[j].is_ascii_alphabetic() || b[j] == b'_') {
                spans.push((start, j));
            }
            i = j;
        } else {
            i += 1;
        }
    }
    spans
}

/// One mutation of a binary input: bytes overwritten, a run of bytes dropped, or the file cut short.
pub fn mutate_bytes(bytes: &[u8], d: &mut Draw) -> (Vec<u8>, String) {
    let mut out = bytes.to_vec();
    match d.below(3) {
        0 => {
            let n = 1 + d.below(8);
            for _ in 0..n {
                let i = d.below(out.len());
                out[i] = d.next() as u8;
            }
            (out, format!("{n} bytes overwritten"))
        }
        1 => {
            let a = d.below(out.len());
            let b = (a + 1 + d.below(64)).min(out.len());
            out.drain(a..b);
            (out, format!("bytes {a}..{b} dropped"))
        }
        _ => {
            let cut = d.below(out.len());
            out.truncate(cut);
            (out, format!("cut at byte {cut}"))
        }
    }
}
