//! WGSL through naga: validation with readable errors, struct layout reflection (so host
//! `#[repr(C)]` types can be checked against the shader's view), and generation of the code that
//! moves a struct to and from a flat array of u32 words, which is how every queue stores items.

use crate::error::RunError;

/// Parses and validates `source` with naga (all capabilities); an error is a
/// [`RunError::Program`] whose message starts with `label` and carries naga's line/column report.
pub fn validate(label: &str, source: &str) -> Result<naga::Module, RunError> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| RunError::Program(format!("{label}: {}", e.emit_to_string(source))))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| RunError::Program(format!("{label}: {}", e.emit_to_string(source))))?;
    Ok(module)
}

/// A constant table as a WGSL function, `fn NAME(i: u32) -> u32`: entry `i` of `values`, as a
/// chain of `select`s over the entries that differ from the most common value (which an index
/// past the end gets, as a clamped array access would get some entry: callers index within it).
/// A table of one value is that constant, whatever the index.
/// The scheduler's tables (threads, words and emits per procedure) are indexed by values known
/// only at run time, and naga writes such an access to a `const` array as a store of the whole
/// array into a function variable, then a load (SPIR-V has no dynamic extract): every strategy
/// calls these instead (`Program::tables_wgsl`; the megakernel keeps threads per item as an
/// array). Selects on a value known at compile time fold away.
pub fn table_fn(name: &str, values: &[u32]) -> String {
    let mut counts = std::collections::BTreeMap::new();
    for &v in values {
        *counts.entry(v).or_insert(0usize) += 1;
    }
    // Most common first, the smaller value on a tie: the same text for the same table.
    let common = counts
        .iter()
        .max_by_key(|&(&v, &c)| (c, std::cmp::Reverse(v)))
        .map_or(0, |(&v, _)| v);
    let mut s = format!("fn {name}(i: u32) -> u32 {{\n    var r = {common}u;\n");
    for (i, &v) in values.iter().enumerate() {
        if v != common {
            s += &format!("    r = select(r, {v}u, i == {i}u);\n");
        }
    }
    s + "    return r;\n}\n"
}

/// One 32-bit scalar of a struct, flattened: the WGSL expression that reaches it from the struct
/// value (e.g. `.cp[3].x`), its word offset, and its scalar kind.
#[derive(Debug, Clone, PartialEq)]
pub struct Leaf {
    /// WGSL access path from the struct value, e.g. `.inner.a.x`.
    pub path: String,
    /// Offset in u32 words from the start of the struct.
    pub word: u32,
    /// The scalar's type.
    pub kind: ScalarKind,
}

/// The 32-bit scalar types an item can carry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ScalarKind {
    /// `u32`.
    U32,
    /// `i32`.
    I32,
    /// `f32`.
    F32,
}

/// The layout of a WGSL struct as naga computes it for storage buffers.
#[derive(Debug, Clone, PartialEq)]
pub struct StructLayout {
    /// The struct's WGSL name.
    pub name: String,
    /// Size in bytes (a multiple of the alignment, as `array<T>` strides it).
    pub size: u32,
    /// Top-level members: (name, byte offset).
    pub members: Vec<(String, u32)>,
    /// Every scalar, flattened.
    pub leaves: Vec<Leaf>,
}

impl StructLayout {
    /// Size in u32 words.
    pub fn words(&self) -> u32 {
        self.size / 4
    }
}

/// Reflects struct `name` declared in `source` (which may contain other declarations), as
/// naga lays it out in a storage buffer; check a `#[repr(C)]` host twin against `size` and
/// `members`. Errors: [`RunError::Program`] if `source` does not parse, has no struct `name`,
/// or the struct holds something that cannot travel in a queue (not a 32-bit scalar, vector,
/// matrix, fixed-size array or struct of those).
pub fn struct_layout(source: &str, name: &str) -> Result<StructLayout, RunError> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| {
        RunError::Program(format!(
            "item struct `{name}`: {}",
            e.emit_to_string(source)
        ))
    })?;
    let mut layouter = naga::proc::Layouter::default();
    layouter
        .update(module.to_ctx())
        .map_err(|e| RunError::Program(format!("layout of `{name}`: {e}")))?;
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .ok_or_else(|| RunError::Program(format!("no struct `{name}` in the item WGSL")))?;
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        return Err(RunError::Program(format!("`{name}` is not a struct")));
    };
    let mut leaves = Vec::new();
    flatten(&module, handle, String::new(), 0, &mut leaves, name)?;
    Ok(StructLayout {
        name: name.to_string(),
        size: layouter[handle].size,
        members: members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
            .collect(),
        leaves,
    })
}

fn flatten(
    module: &naga::Module,
    ty: naga::Handle<naga::Type>,
    path: String,
    byte: u32,
    out: &mut Vec<Leaf>,
    owner: &str,
) -> Result<(), RunError> {
    let scalar_kind = |s: naga::Scalar, path: &str| -> Result<ScalarKind, RunError> {
        match (s.kind, s.width) {
            (naga::ScalarKind::Uint, 4) => Ok(ScalarKind::U32),
            (naga::ScalarKind::Sint, 4) => Ok(ScalarKind::I32),
            (naga::ScalarKind::Float, 4) => Ok(ScalarKind::F32),
            _ => Err(RunError::Program(format!(
                "item struct `{owner}` field `{path}`: only 32-bit u32/i32/f32 scalars can travel in a queue"
            ))),
        }
    };
    match &module.types[ty].inner {
        naga::TypeInner::Scalar(s) => out.push(Leaf {
            kind: scalar_kind(*s, &path)?,
            path,
            word: byte / 4,
        }),
        naga::TypeInner::Vector { size, scalar } => {
            let kind = scalar_kind(*scalar, &path)?;
            for (i, c) in ["x", "y", "z", "w"].iter().take(*size as usize).enumerate() {
                out.push(Leaf {
                    path: format!("{path}.{c}"),
                    word: byte / 4 + i as u32,
                    kind,
                });
            }
        }
        naga::TypeInner::Matrix {
            columns,
            rows,
            scalar,
        } => {
            let kind = scalar_kind(*scalar, &path)?;
            let col_stride = if *rows == naga::VectorSize::Tri {
                4
            } else {
                *rows as u32
            };
            for c in 0..*columns as u32 {
                for r in 0..*rows as u32 {
                    out.push(Leaf {
                        path: format!("{path}[{c}][{r}]"),
                        word: byte / 4 + c * col_stride + r,
                        kind,
                    });
                }
            }
        }
        naga::TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            stride,
        } => {
            for i in 0..n.get() {
                flatten(
                    module,
                    *base,
                    format!("{path}[{i}]"),
                    byte + i * stride,
                    out,
                    owner,
                )?;
            }
        }
        naga::TypeInner::Struct { members, .. } => {
            for m in members {
                let name = m.name.clone().unwrap_or_default();
                flatten(
                    module,
                    m.ty,
                    format!("{path}.{name}"),
                    byte + m.offset,
                    out,
                    owner,
                )?;
            }
        }
        other => {
            return Err(RunError::Program(format!(
                "item struct `{owner}` field `{path}`: type {other:?} cannot travel in a queue"
            )));
        }
    }
    Ok(())
}

/// Whether items of `layout` move as 16-byte vectors: their size is a whole number of
/// `vec4<u32>`. Queue regions and outboxes start on 16-byte boundaries
/// (`QueueLayout::new`), so such an item's first word is always 4-aligned.
pub(crate) fn moves_by_vec4(layout: &StructLayout) -> bool {
    layout.words().is_multiple_of(4)
}

/// Generates `fn {prefix}_load_{T}(base: u32) -> T` and `fn {prefix}_store_{T}(base: u32, v: T)`
/// over the word accessors `{prefix}_load_word(i) -> u32` and `{prefix}_store_word(i, w)`, or,
/// for items that [`moves_by_vec4`], over `{prefix}_load_vec4(i) -> vec4<u32>` and
/// `{prefix}_store_vec4(i, v)` (i a 4-aligned word index).
///
/// Why vectors: a one-thread item is read and written by its own thread, so a warp touches 32
/// items at a stride of the item size. Word by word, each of those accesses is its own memory
/// transaction; 16 bytes at a time there are a quarter as many (on the H200 the 256-byte items
/// of the large-payload tree moved several times faster: docs/results.md, "Large items: how they
/// are copied").
pub(crate) fn load_store_fns(layout: &StructLayout, prefix: &str) -> String {
    let t = &layout.name;
    let mut s = format!("fn {prefix}_load_{t}(base: u32) -> {t} {{\n    var v: {t};\n");
    if moves_by_vec4(layout) {
        for g in 0..layout.words() / 4 {
            s += &format!("    let g{g} = {prefix}_load_vec4(base + {}u);\n", g * 4);
        }
        for l in &layout.leaves {
            let w = format!("g{}[{}]", l.word / 4, l.word % 4);
            s += &format!("    v{} = {};\n", l.path, cast_in(l, w));
        }
    } else {
        for l in &layout.leaves {
            let w = format!("{prefix}_load_word(base + {}u)", l.word);
            s += &format!("    v{} = {};\n", l.path, cast_in(l, w));
        }
    }
    s += "    return v;\n}\n";
    s += &format!("fn {prefix}_store_{t}(base: u32, v: {t}) {{\n");
    if moves_by_vec4(layout) {
        // Padding words (between members) have no leaf: they are stored as 0.
        let mut words = vec!["0u".to_string(); layout.words() as usize];
        for l in &layout.leaves {
            words[l.word as usize] = cast_out(l);
        }
        for (g, c) in words.chunks(4).enumerate() {
            s += &format!(
                "    {prefix}_store_vec4(base + {}u, vec4<u32>({}));\n",
                g * 4,
                c.join(", ")
            );
        }
    } else {
        for l in &layout.leaves {
            s += &format!(
                "    {prefix}_store_word(base + {}u, {});\n",
                l.word,
                cast_out(l)
            );
        }
    }
    s += "}\n";
    s
}

/// The WGSL that turns stored word `w` into the scalar of leaf `l`.
pub(crate) fn cast_in(l: &Leaf, w: String) -> String {
    match l.kind {
        ScalarKind::U32 => w,
        ScalarKind::I32 => format!("bitcast<i32>({w})"),
        ScalarKind::F32 => format!("bitcast<f32>({w})"),
    }
}

/// The WGSL that turns leaf `l` of a value `v` into the word stored.
pub(crate) fn cast_out(l: &Leaf) -> String {
    match l.kind {
        ScalarKind::U32 => format!("v{}", l.path),
        _ => format!("bitcast<u32>(v{})", l.path),
    }
}

/// The value of `const NAME: u32 = Nu;` at the start of a line of `src` (a WGSL template):
/// tests check host twins of shader layouts with it.
#[cfg(test)]
pub(crate) fn wgsl_const(src: &str, name: &str) -> Option<usize> {
    let line = src
        .lines()
        .find(|l| l.starts_with(&format!("const {name}: u32 = ")))?;
    let v = line.split('=').nth(1)?.trim().split('u').next()?;
    v.parse().ok()
}

/// WGSL accessors `{prefix}_load_word`, `{prefix}_store_word`, `{prefix}_load_vec4` and
/// `{prefix}_store_vec4` over `buffer`, a storage `array<vec4<u32>>` addressed in u32 words
/// (`*_vec4` take a 4-aligned word index).
pub(crate) fn vec4_word_accessors(prefix: &str, buffer: &str) -> String {
    format!(
        "fn {prefix}_load_word(i: u32) -> u32 {{ return {buffer}[i >> 2u][i & 3u]; }}\n\
         fn {prefix}_store_word(i: u32, sched_w: u32) {{ {buffer}[i >> 2u][i & 3u] = sched_w; }}\n\
         fn {prefix}_load_vec4(i: u32) -> vec4<u32> {{ return {buffer}[i >> 2u]; }}\n\
         fn {prefix}_store_vec4(i: u32, sched_v: vec4<u32>) {{ {buffer}[i >> 2u] = sched_v; }}\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const SRC: &str = "struct Inner { a: vec3<f32>, b: u32 }
        struct Item { id: u32, p: array<vec4<f32>, 2>, inner: Inner, k: i32 }";

    /// A table as selects over the entries that differ from its most common value; one value
    /// is a constant; either is valid WGSL.
    #[test]
    fn a_table_function_selects_only_the_uncommon_entries() {
        let f = table_fn("f", &[2, 0, 2, 5]);
        assert_eq!(
            f,
            "fn f(i: u32) -> u32 {\n    var r = 2u;\n    r = select(r, 0u, i == 1u);\n    \
             r = select(r, 5u, i == 3u);\n    return r;\n}\n"
        );
        let one = table_fn("g", &[3, 3]);
        assert_eq!(
            one,
            "fn g(i: u32) -> u32 {\n    var r = 3u;\n    return r;\n}\n"
        );
        validate("tables", &(f + &one)).unwrap();
    }

    #[test]
    fn layout_follows_wgsl_alignment_rules() {
        let l = struct_layout(SRC, "Item").unwrap();
        // id at 0, p (align 16) at 16..48, inner (align 16) at 48..64, k at 64; size rounds to 80.
        assert_eq!(
            l.members,
            vec![
                ("id".into(), 0),
                ("p".into(), 16),
                ("inner".into(), 48),
                ("k".into(), 64)
            ]
        );
        assert_eq!(l.size, 80);
        assert_eq!(l.leaves.len(), 1 + 8 + 4 + 1);
        assert_eq!(
            l.leaves[9],
            Leaf {
                path: ".inner.a.x".into(),
                word: 12,
                kind: ScalarKind::F32
            }
        );
        assert_eq!(
            l.leaves[12],
            Leaf {
                path: ".inner.b".into(),
                word: 15,
                kind: ScalarKind::U32
            }
        );
    }

    #[test]
    fn generated_load_store_is_valid_wgsl() {
        // Item (20 words) moves by vec4; Odd (3 words) word by word.
        let odd = "struct Odd { a: u32, b: f32, c: i32 }";
        let l = struct_layout(SRC, "Item").unwrap();
        let o = struct_layout(odd, "Odd").unwrap();
        assert!(moves_by_vec4(&l) && !moves_by_vec4(&o));
        let item_fns = load_store_fns(&l, "q");
        assert!(item_fns.contains("q_load_vec4(base + 16u)"), "{item_fns}");
        assert!(!load_store_fns(&o, "q").contains("vec4"));
        let src = format!(
            "{SRC}\n{odd}\n@group(0) @binding(0) var<storage, read_write> buf: array<vec4<u32>>;\n\
             {}{item_fns}{}\n\
             @compute @workgroup_size(1) fn main() {{ q_store_Item(20u, q_load_Item(0u)); q_store_Odd(41u, q_load_Odd(1u)); }}",
            vec4_word_accessors("q", "buf"),
            load_store_fns(&o, "q")
        );
        validate("test", &src).unwrap();
    }

    #[test]
    fn unsupported_field_types_are_rejected_by_name() {
        let e = struct_layout("struct X { a: f16 }", "X");
        assert!(e.is_err());
        let e = struct_layout("struct X { a: vec2<u32>, b: atomic<u32> }", "X").unwrap_err();
        assert!(e.to_string().contains(".b"), "{e}");
    }
}
