//! The validation of [`Program::new`]: the program's shared WGSL (item structs, user
//! WGSL, bodies) compiled on its own with stub `enqueue_*` functions, so that an error is
//! reported where the user wrote it (a procedure's body and a line of that body) rather than
//! at a line of a strategy's generated shader. A bracket a part leaves unclosed (naga then
//! stumbles at the next part) is reported in the part that opened it. After naga has parsed and
//! validated that source, its module is checked for what naga cannot know:
//! - every procedure has `fn <name>_execute(item: <Item>, inv: Invocation)` with no result;
//! - a procedure's execute function, and every function it calls, directly or not, calls
//!   `enqueue_<t>` only for targets `t` the procedure declared with `.emits(t, n)`, `n > 0`
//!   (a static call graph: a call that is never taken still counts);
//! - every `@group(1)` variable has a [`crate::UserBindings`] layout entry of the same binding
//!   and access, and nothing but the scheduler uses another group.
//!
//! Then naga's SPIR-V backend writes every execute function, as wgpu will when a strategy makes
//! its pipeline, so that a panic of that backend on code its validator accepted is an error
//! naming the procedure (`check_spirv`).

use naga::{Block, Handle, Span, Statement};

use super::{Part, Program};
use crate::error::RunError;

/// The shared WGSL with enqueue stubs, and the byte range of each part in it.
struct SharedSource<'a> {
    program: &'a Program,
    text: String,
    parts: Vec<(Part, usize, usize)>,
}

impl<'a> SharedSource<'a> {
    fn new(program: &'a Program) -> SharedSource<'a> {
        let mut shared = SharedSource {
            program,
            text: String::new(),
            parts: Vec::new(),
        };
        for (part, text) in program.common_parts() {
            shared.push(part, &text);
        }
        let stubs: String = program
            .procs
            .iter()
            .map(|p| {
                format!(
                    "fn enqueue_{n}(item: {}) {{}}\n\
                     fn reserve_{n}() -> ItemSlot {{ return ItemSlot(0xffffffffu, 1u, 0u); }}\n",
                    p.layout.name,
                    n = p.proc.name
                )
            })
            .collect::<String>()
            + "fn store_word(slot: ItemSlot, word: u32, value: u32) {}\n\
               const SCHED_MEGAKERNEL: bool = false;\n";
        shared.push(
            Part::Generated,
            &format!("{stubs}@compute @workgroup_size(1) fn sched_validation() {{}}"),
        );
        shared
    }

    fn push(&mut self, part: Part, text: &str) {
        let start = self.text.len();
        self.text += text;
        self.parts.push((part, start, self.text.len()));
        self.text += "\n";
    }

    /// The part holding byte `offset` and where that part starts.
    fn part_at(&self, offset: usize) -> Option<(&Part, usize)> {
        self.parts
            .iter()
            .find(|(_, start, end)| (*start..=*end).contains(&offset))
            .map(|(part, start, _)| (part, *start))
    }

    fn describe(&self, part: &Part) -> String {
        let name = |i: usize| &self.program.procs[i].proc.name;
        match part {
            Part::Generated => "generated code".into(),
            Part::Item(t) => format!("item struct `{t}`"),
            Part::Shared(i) => format!("`.shared(...)` of procedure `{}`", name(*i)),
            Part::User => "user WGSL (UserBindings::wgsl)".into(),
            Part::Body(i) => format!("procedure `{}`, body", name(*i)),
        }
    }

    /// `<part> line L, column C` for a span, lines and columns counted from 1 within the part.
    fn locate(&self, span: Span) -> Option<(String, usize, usize, &str)> {
        let range = span.to_range()?;
        let (part, start) = self.part_at(range.start)?;
        let before = &self.text[start..range.start];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(start, |i| start + i + 1);
        let column = range.start - line_start + 1;
        let line_end = self.text[line_start..]
            .find('\n')
            .map_or(self.text.len(), |i| line_start + i);
        Some((
            format!("{} line {line}, column {column}", self.describe(part)),
            line,
            column,
            &self.text[line_start..line_end],
        ))
    }

    /// The first bracket (`{`, `(`, `[`) that a part the user wrote leaves unclosed, or a
    /// closing one without its opener, described with its location. Comments are skipped.
    fn unbalanced(&self) -> Option<String> {
        for (part, start, end) in &self.parts {
            if *part == Part::Generated {
                continue;
            }
            let text = &self.text[*start..*end];
            let bytes = text.as_bytes();
            let mut open: Vec<(u8, usize)> = Vec::new();
            let mut bad = None;
            let mut i = 0;
            while i < bytes.len() && bad.is_none() {
                match bytes[i] {
                    b'/' if bytes.get(i + 1) == Some(&b'/') => {
                        i = text[i..].find('\n').map_or(bytes.len(), |n| i + n);
                    }
                    b'/' if bytes.get(i + 1) == Some(&b'*') => {
                        // WGSL block comments nest.
                        let mut depth = 0;
                        while i < bytes.len() {
                            if bytes[i..].starts_with(b"/*") {
                                depth += 1;
                                i += 2;
                            } else if bytes[i..].starts_with(b"*/") {
                                depth -= 1;
                                i += 2;
                                if depth == 0 {
                                    break;
                                }
                            } else {
                                i += 1;
                            }
                        }
                        continue;
                    }
                    c @ (b'{' | b'(' | b'[') => open.push((c, i)),
                    c @ (b'}' | b')' | b']') => {
                        let opener = match c {
                            b'}' => b'{',
                            b')' => b'(',
                            _ => b'[',
                        };
                        match open.pop() {
                            Some((o, _)) if o == opener => {}
                            _ => bad = Some((c, i, "has no opening bracket in it")),
                        }
                    }
                    _ => {}
                }
                i += 1;
            }
            let bad = bad.or_else(|| open.first().map(|&(c, i)| (c, i, "is not closed in it")));
            if let Some((c, i, what)) = bad {
                let span = Span::new((start + i) as u32, (start + i + 1) as u32);
                let (at, ..) = self.locate(span)?;
                return Some(format!("{at}: this `{}` {what}", c as char));
            }
        }
        None
    }

    fn is_generated(&self, span: Span) -> bool {
        span.to_range()
            .and_then(|r| self.part_at(r.start))
            .is_none_or(|(part, _)| *part == Part::Generated)
    }

    /// A report of naga's `message` with its labelled spans, each located within its part. The
    /// first span in code the user wrote (the last one if `innermost_last`: naga's validator
    /// lists the function before the expression in it) heads the report.
    fn report(
        &self,
        message: &str,
        spans: &[(Span, String)],
        notes: &[String],
        innermost_last: bool,
    ) -> String {
        let user = |i: &usize| !self.is_generated(spans[*i].0);
        let primary = if innermost_last {
            (0..spans.len()).rev().find(user)
        } else {
            (0..spans.len()).find(user)
        }
        .or((!spans.is_empty()).then_some(0));
        let mut out = match primary.and_then(|i| self.locate(spans[i].0)) {
            Some((at, ..)) => format!("{at}: {message}"),
            None => message.to_string(),
        };
        let order = primary
            .into_iter()
            .chain((0..spans.len()).filter(|&i| Some(i) != primary));
        for i in order {
            let (span, label) = &spans[i];
            let Some((at, line, column, text)) = self.locate(*span) else {
                continue;
            };
            let width = line.to_string().len();
            let length = span.to_range().map_or(1, |r| r.len().max(1));
            let length = length.min(text.len().saturating_sub(column - 1).max(1));
            out += &format!(
                "\n{:width$}--> {at}\n{line} | {text}\n{:width$} | {}{} {label}",
                "",
                "",
                " ".repeat(column - 1),
                "^".repeat(length),
            );
        }
        for note in notes {
            out += &format!("\nnote: {note}");
        }
        out
    }
}

/// Compiles `program`'s shared WGSL with enqueue stubs and checks it (see the module docs).
/// Every error is a [`RunError::Program`] naming the procedure, part and line it is about.
/// Returns performance notes ([`Program::notes`](crate::Program::notes)).
///
/// The source is parsed and validated once, with the SPIR-V check's entry points appended
/// (`spirv_entry_points`): one parse of the program instead of two, about 10-15 ms of every
/// `Program::new` for Reyes' four procedures on the dev machine. Where that source fails, the
/// plain one is parsed and validated again for the user's error, which then names what the
/// user wrote, and the SPIR-V check is skipped as before (a failure of the appended entry
/// points alone is not the user's: the strategies' own compilation reports it).
pub(crate) fn check(program: &Program) -> Result<Vec<String>, RunError> {
    let shared = SharedSource::new(program);
    let own = spirv_checked(&shared);
    let with_entries = shared.text.clone() + &spirv_entry_points(&own);
    if let Some((module, info)) = parse_and_validate(&with_entries) {
        check_module(&shared, &module)?;
        check_spirv(&own, &module, &info)?;
        return Ok(dynamic_item_indexing(&shared, &module, &info));
    }
    let module = naga::front::wgsl::parse_str(&shared.text).map_err(|e| {
        let spans: Vec<(Span, String)> = e.labels().map(|(s, l)| (s, l.to_string())).collect();
        let notes: Vec<String> = e.notes().map(str::to_string).collect();
        let report = shared.report(e.message(), &spans, &notes, false);
        // An unclosed bracket makes naga report the next part's first line: name the part.
        RunError::Program(match shared.unbalanced() {
            Some(at) => format!("{at}\nnaga's error, which follows from it: {report}"),
            None => report,
        })
    })?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module);
    let info = info.map_err(|e| {
        // naga's chain runs from the function to the innermost cause: lead with the cause.
        let mut chain = vec![e.as_inner().to_string()];
        let mut source: &dyn std::error::Error = e.as_inner();
        while let Some(next) = source.source() {
            chain.push(next.to_string());
            source = next;
        }
        let message = chain.pop().unwrap_or_default();
        let spans: Vec<(Span, String)> = e.spans().cloned().collect();
        let mut report = shared.report(&message, &spans, &chain, true);
        // A call's argument of the wrong type names neither the function nor the type.
        if message.contains("doesn't match the type") && report.contains("store_word(") {
            report += "\nhint: store_word(slot, word, value) takes value as a u32: store an \
                       f32 or i32 as bitcast<u32>(value)";
        }
        RunError::Program(report)
    })?;
    check_module(&shared, &module)?;
    log::debug!("SPIR-V check skipped: the source with its entry points does not compile");
    Ok(dynamic_item_indexing(&shared, &module, &info))
}

/// What naga cannot know (the module docs' list), checked on a module that compiled.
fn check_module(shared: &SharedSource, module: &naga::Module) -> Result<(), RunError> {
    check_execute_functions(shared, module)?;
    check_enqueue_targets(shared, module)?;
    check_user_bindings(shared, module)
}

/// `text` parsed and validated by naga, or `None` where either fails.
fn parse_and_validate(text: &str) -> Option<(naga::Module, naga::valid::ModuleInfo)> {
    let module = naga::front::wgsl::parse_str(text).ok()?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .ok()?;
    Some((module, info))
}

/// The procedures whose execute function the SPIR-V check writes: a procedure that runs
/// another's execute function (`Procedure::execute_of`) is checked through that one.
fn spirv_checked<'p>(shared: &SharedSource<'p>) -> Vec<&'p super::ProcInfo> {
    (shared.program.procs.iter())
        .filter(|p| p.proc.execute_of.is_none())
        .collect()
}

/// One compute entry point per procedure in `own`, `sched_spirv_<name>`, that calls its
/// execute function: what `check_spirv` writes as SPIR-V.
fn spirv_entry_points(own: &[&super::ProcInfo]) -> String {
    own.iter()
        .map(|p| {
            format!(
                "@compute @workgroup_size(1) fn sched_spirv_{name}() {{\n    var item: {ty};\n    \
                 {name}_execute(item, Invocation(0u, 0u, true, {threads}u));\n}}\n",
                name = p.proc.name,
                ty = p.layout.name,
                threads = p.proc.threads_per_item
            )
        })
        .collect()
}

/// Writes each procedure's execute function (its `sched_spirv_<name>` entry point in
/// `module`) as SPIR-V with naga's backend, as wgpu's Vulkan backend does when a strategy's
/// pipeline is made, and turns a failure or a panic of that backend on code its validator
/// accepted into a [`RunError::Program`] naming the procedure; without it the panic reached
/// the caller of `Megakernel::new` or `Kernels::new`. One known cause in naga 30.0.1: a
/// pointer to a member of a struct passed to a function (`f(&item.cp)`, "Expression [N] is
/// not cached"). The default panic hook still prints naga's message before the error is
/// returned.
fn check_spirv(
    own: &[&super::ProcInfo],
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
) -> Result<(), RunError> {
    use naga::back::spv;
    let start = std::time::Instant::now();
    // The bounds-check policies wgpu-hal 30.0.1's Vulkan backend uses with checks on.
    let restrict = naga::proc::BoundsCheckPolicy::Restrict;
    let options = spv::Options {
        bounds_check_policies: naga::proc::BoundsCheckPolicies {
            index: restrict,
            buffer: restrict,
            image_load: restrict,
            binding_array: naga::proc::BoundsCheckPolicy::Unchecked,
        },
        ..Default::default()
    };
    for p in own {
        let entry = format!("sched_spirv_{}", p.proc.name);
        let pipeline = spv::PipelineOptions {
            shader_stage: naga::ShaderStage::Compute,
            entry_point: entry,
        };
        let written = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            spv::write_vec(module, info, &options, Some(&pipeline))
        }));
        let why = match written {
            Ok(Ok(_)) => continue,
            Ok(Err(e)) => format!("fails: {e}"),
            Err(panic) => {
                let message = (panic.downcast_ref::<String>().cloned())
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                format!("panics: {message}")
            }
        };
        return Err(RunError::Program(format!(
            "procedure `{}`: naga's SPIR-V backend, which wgpu runs when a pipeline is made, \
             {why}. The body passed validation, so this is a naga bug; a known cause is a \
             pointer to a member of a struct passed to a function (`f(&item.cp)`): copy the \
             member into a local `var` and pass a pointer to that (docs/scheduler.md, section \
             1, `Program::new`). A panic message printed above is this one, caught",
            p.proc.name
        )));
    }
    log::debug!(
        "SPIR-V of {} execute functions written by naga: {:.1} ms",
        own.len(),
        start.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}

/// Notes for each run-time index into an array or matrix reached from a parameter (a value)
/// of a function the user wrote (bodies and user WGSL; an execute function's `item`, or a
/// helper's), without a `var` in between: naga's SPIR-V backend spills the indexed value to a
/// temporary at every such access (`spill_to_internal_variable` in naga's `back/spv`).
fn dynamic_item_indexing(
    shared: &SharedSource,
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
) -> Vec<String> {
    let mut notes = Vec::new();
    for (h, f) in module.functions.iter() {
        if shared.is_generated(module.functions.get_span(h)) {
            continue;
        }
        for (e, expr) in f.expressions.iter() {
            let naga::Expression::Access { base, .. } = *expr else {
                continue;
            };
            let mut root = base;
            while let naga::Expression::Access { base, .. }
            | naga::Expression::AccessIndex { base, .. } = f.expressions[root]
            {
                root = base;
            }
            let indexed = info[h][base].ty.inner_with(&module.types);
            let spills = matches!(
                indexed,
                naga::TypeInner::Array { .. } | naga::TypeInner::Matrix { .. }
            );
            let naga::Expression::FunctionArgument(arg) = f.expressions[root] else {
                continue;
            };
            if !spills {
                continue;
            }
            let fname = f.name.as_deref().unwrap_or("?");
            let param = f.arguments[arg as usize].name.as_deref().unwrap_or("?");
            let at = shared
                .locate(f.expressions.get_span(e))
                .map(|(at, ..)| format!("{at}: "))
                .unwrap_or_default();
            notes.push(format!(
                "{at}a run-time index into an array of `{param}`, a parameter of `{fname}` (a \
                 value), copies the whole array at every access (naga's SPIR-V). Copy it into a \
                 `var` under another name once (e.g. `fn {fname}({param}_value: ...) {{ var {param} = \
                 {param}_value; ...`) and index that (docs/scheduler.md, \"Writing fast procedures\")"
            ));
        }
    }
    notes
}

fn function(module: &naga::Module, name: &str) -> Option<Handle<naga::Function>> {
    module
        .functions
        .iter()
        .find(|(_, f)| f.name.as_deref() == Some(name))
        .map(|(h, _)| h)
}

fn type_name(module: &naga::Module, ty: Handle<naga::Type>) -> String {
    module.types[ty]
        .name
        .clone()
        .unwrap_or_else(|| "an unnamed type".into())
}

/// Every procedure `p` has `fn <p>_execute(item: <Item>, inv: Invocation)` without a result.
/// It may be defined in any body or in the user WGSL (Reyes defines two procedures' execute
/// functions in one body).
fn check_execute_functions(shared: &SharedSource, module: &naga::Module) -> Result<(), RunError> {
    for (i, p) in shared.program.procs.iter().enumerate() {
        if p.proc.execute_of.is_some() {
            continue; // the other procedure's function, checked there (Program::new)
        }
        let name = &p.proc.name;
        let item = &p.layout.name;
        let expected = format!("fn {name}_execute(item: {item}, inv: Invocation)");
        let Some(h) = function(module, &format!("{name}_execute")) else {
            // Name what the body does define: usually the misspelt execute function.
            let defined: Vec<String> = module
                .functions
                .iter()
                .filter(|(h, _)| {
                    let span = module.functions.get_span(*h);
                    span.to_range()
                        .and_then(|r| shared.part_at(r.start))
                        .is_some_and(|(part, _)| *part == Part::Body(i))
                })
                .filter_map(|(_, f)| f.name.clone())
                .collect();
            let found = if defined.is_empty() {
                "its body defines no function".to_string()
            } else {
                format!("its body defines {}", defined.join(", "))
            };
            return Err(RunError::Program(format!(
                "procedure `{name}`: no `{expected}` in the program's WGSL ({found})"
            )));
        };
        let f = &module.functions[h];
        let types: Vec<String> = f
            .arguments
            .iter()
            .map(|a| type_name(module, a.ty))
            .collect();
        if types != [item.as_str(), "Invocation"] || f.result.is_some() {
            let at = shared
                .locate(module.functions.get_span(h))
                .map(|(at, ..)| format!(" ({at})"))
                .unwrap_or_default();
            let result = if f.result.is_some() {
                " and returns a value"
            } else {
                ""
            };
            return Err(RunError::Program(format!(
                "procedure `{name}`: `{name}_execute`{at} takes ({}){result}; it must be `{expected}` \
                 with no result",
                types.join(", ")
            )));
        }
    }
    Ok(())
}

/// Functions each function calls, by function index.
fn call_graph(module: &naga::Module) -> Vec<Vec<Handle<naga::Function>>> {
    fn visit(block: &Block, out: &mut Vec<Handle<naga::Function>>) {
        for statement in block.iter() {
            match statement {
                Statement::Call { function, .. } => out.push(*function),
                Statement::Block(b) => visit(b, out),
                Statement::If { accept, reject, .. } => {
                    visit(accept, out);
                    visit(reject, out);
                }
                Statement::Switch { cases, .. } => cases.iter().for_each(|c| visit(&c.body, out)),
                Statement::Loop {
                    body, continuing, ..
                } => {
                    visit(body, out);
                    visit(continuing, out);
                }
                _ => {}
            }
        }
    }
    module
        .functions
        .iter()
        .map(|(_, f)| {
            let mut calls = Vec::new();
            visit(&f.body, &mut calls);
            calls
        })
        .collect()
}

/// Every `enqueue_<t>` reachable from `<p>_execute` in the call graph is a target `p` declared.
fn check_enqueue_targets(shared: &SharedSource, module: &naga::Module) -> Result<(), RunError> {
    let calls = call_graph(module);
    let procs = &shared.program.procs;
    // Per target, its `enqueue_<t>` and `reserve_<t>` stubs.
    let enqueue: Vec<Vec<Handle<naga::Function>>> = procs
        .iter()
        .map(|t| {
            ["enqueue", "reserve"]
                .iter()
                .filter_map(|f| function(module, &format!("{f}_{}", t.proc.name)))
                .collect()
        })
        .collect();
    let name_of = |h: Handle<naga::Function>| module.functions[h].name.clone().unwrap_or_default();
    for p in procs {
        let Some(root) = function(module, &p.proc.execute_fn()) else {
            continue;
        };
        // Depth-first from the execute function, remembering how each function was reached.
        let mut parent: Vec<Option<Option<Handle<naga::Function>>>> =
            vec![None; module.functions.len()];
        parent[root.index()] = Some(None);
        let mut stack = vec![root];
        while let Some(f) = stack.pop() {
            for &g in &calls[f.index()] {
                if parent[g.index()].is_none() {
                    parent[g.index()] = Some(Some(f));
                    stack.push(g);
                }
            }
        }
        for (t, target) in procs.iter().enumerate() {
            if p.emits[t] > 0 {
                continue;
            }
            let Some(&stub) = enqueue[t].iter().find(|s| parent[s.index()].is_some()) else {
                continue;
            };
            let mut path = vec![name_of(stub)];
            let mut at = stub;
            while let Some(Some(up)) = parent[at.index()] {
                path.push(name_of(up));
                at = up;
            }
            path.reverse();
            return Err(RunError::Program(format!(
                "procedure `{}` enqueues to `{}` ({}) but declares no `.emits(\"{}\", n)`: declare \
                 the most items one `{}` item may emit to `{}`",
                p.proc.name,
                target.proc.name,
                path.join(" -> "),
                target.proc.name,
                p.proc.name,
                target.proc.name
            )));
        }
    }
    Ok(())
}

/// `@group(1)` variables match the user layout entries; no other group but the scheduler's.
fn check_user_bindings(shared: &SharedSource, module: &naga::Module) -> Result<(), RunError> {
    let layout = &shared.program.user.layout;
    for (h, var) in module.global_variables.iter() {
        let Some(binding) = &var.binding else {
            continue;
        };
        let name = var.name.as_deref().unwrap_or("?");
        let at = shared
            .locate(module.global_variables.get_span(h))
            .map(|(at, ..)| format!(" ({at})"))
            .unwrap_or_default();
        if binding.group != 1 {
            return Err(RunError::Program(format!(
                "`{name}`{at} is in @group({}): user resources go in @group(1) (group 0 is the \
                 scheduler's)",
                binding.group
            )));
        }
        let Some(entry) = layout.iter().find(|e| e.binding == binding.binding) else {
            return Err(RunError::Program(format!(
                "`{name}`{at} is @group(1) @binding({}), but UserBindings::layout has no entry \
                 for binding {}",
                binding.binding, binding.binding
            )));
        };
        if let naga::AddressSpace::Storage { access } = var.space {
            let read_write = access.contains(naga::StorageAccess::STORE);
            let entry_read_only = match entry.ty {
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only },
                    ..
                } => read_only,
                _ => {
                    return Err(RunError::Program(format!(
                        "`{name}`{at} is a storage buffer, but UserBindings::layout entry {} is \
                         not (use scheduler::storage_entry)",
                        binding.binding
                    )));
                }
            };
            if read_write == entry_read_only {
                let (wgsl, entry) = if read_write {
                    ("read_write", "read-only")
                } else {
                    ("read", "read-write")
                };
                return Err(RunError::Program(format!(
                    "`{name}`{at} is var<storage, {wgsl}> but UserBindings::layout entry {} is \
                     {entry}",
                    binding.binding
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::{ItemType, Procedure, Program, RunError, UserBindings};

    fn word() -> ItemType {
        ItemType::new("Word", "struct Word { v: u32 }")
    }

    fn error(procs: Vec<Procedure>, user: UserBindings) -> String {
        match Program::new(procs, user) {
            Err(RunError::Program(m)) => m,
            Err(e) => panic!("expected a program error, got {e}"),
            Ok(_) => panic!("expected a program error, the program was accepted"),
        }
    }

    fn sink() -> Procedure {
        Procedure::new("sink", word(), 1).body("fn sink_execute(item: Word, inv: Invocation) {}")
    }

    /// naga 30.0.1's SPIR-V backend panics on a pointer to a struct member passed to a
    /// function, which its validator accepts: an error naming the procedure, not a panic when
    /// a strategy makes its pipeline; the same body through a local copy is accepted.
    #[test]
    fn a_body_that_naga_s_spir_v_backend_cannot_write_is_an_error_naming_the_procedure() {
        let item = ItemType::new("Net", "struct Net { cp: array<vec4<f32>, 4>, n: u32 }");
        let program = |call: &str| {
            let body = format!(
                "fn first(a: ptr<function, array<vec4<f32>, 4>>) -> f32 {{ return (*a)[0].x; }}\n\
                 fn net_execute(item_value: Net, inv: Invocation) {{\n    \
                     var item = item_value;\n    {call}\n    \
                     if first(&cp) > 0.0 {{ enqueue_sink(Word(item.n)); }}\n}}"
            );
            let net = Procedure::new("net", item.clone(), 1)
                .emits("sink", 1)
                .body(&body);
            Program::new(vec![net, sink()], UserBindings::none())
        };
        let err = match program("var cp = item.cp; if first(&item.cp) > 1.0 { return; }") {
            Err(RunError::Program(m)) => m,
            Err(e) => panic!("expected a program error, got {e}"),
            Ok(_) => panic!("expected a program error, the program was accepted"),
        };
        assert!(
            err.contains("procedure `net`") && err.contains("SPIR-V") && err.contains("panics"),
            "{err}"
        );
        program("var cp = item.cp;").unwrap();
    }

    #[test]
    fn a_run_time_index_into_the_item_parameter_is_noted_and_a_var_copy_is_not() {
        let item = ItemType::new("Row", "struct Row { n: u32, w: array<u32, 8> }");
        let body = |b: &str| {
            Program::new(
                vec![Procedure::new("row", item.clone(), 1).body(b)],
                UserBindings::none(),
            )
            .unwrap()
        };
        let slow = body(
            "fn row_execute(item: Row, inv: Invocation) {\n    var s = 0u;\n    \
             for (var i = 0u; i < item.n; i++) { s += item.w[i]; }\n}",
        );
        assert_eq!(slow.notes().len(), 1, "{:?}", slow.notes());
        let n = &slow.notes()[0];
        assert!(n.contains("procedure `row`") && n.contains("line 3"), "{n}");
        let fast = body(
            "fn row_execute(item_value: Row, inv: Invocation) {\n    var item = item_value;\n    \
             var s = item.w[3];\n    for (var i = 0u; i < item.n; i++) { s += item.w[i]; }\n}",
        );
        assert!(fast.notes().is_empty(), "{:?}", fast.notes());
        // Through a helper that takes the item (or an array of it) by value: the same copy.
        let helper = body(
            "fn sum(r: Row) -> u32 {\n    var s = 0u;\n    for (var i = 0u; i < r.n; i++) { s += r.w[i]; }\n    return s;\n}\n\
             fn row_execute(item: Row, inv: Invocation) { let s = sum(item); }",
        );
        assert_eq!(helper.notes().len(), 1, "{:?}", helper.notes());
        let n = &helper.notes()[0];
        assert!(
            n.contains("`r`, a parameter of `sum`") && n.contains("line 3"),
            "{n}"
        );
    }

    #[test]
    fn a_procedure_may_run_the_execute_function_of_a_known_one_of_its_item_type_only() {
        let one = Procedure::new("one", word(), 4)
            .body("fn one_execute(item: Word, inv: Invocation) { let t = inv.threads; }");
        let two = Procedure::new("two", word(), 2).execute_of("one");
        Program::new(vec![one.clone(), sink(), two.clone()], UserBindings::none()).unwrap();
        // Unknown, chained or of another item type: refused, naming the procedure.
        let m = error(
            vec![
                one.clone(),
                Procedure::new("two", word(), 2).execute_of("on"),
            ],
            UserBindings::none(),
        );
        assert!(
            m.contains("procedure `two`") && m.contains("unknown `on`"),
            "{m}"
        );
        let three = Procedure::new("three", word(), 1).execute_of("two");
        let m = error(vec![one.clone(), two, three], UserBindings::none());
        assert!(
            m.contains("procedure `three`") && m.contains("`two` itself"),
            "{m}"
        );
        let other = ItemType::new("Pair", "struct Pair { a: u32, b: u32 }");
        let m = error(
            vec![one, Procedure::new("two", other, 2).execute_of("one")],
            UserBindings::none(),
        );
        assert!(m.contains("takes `Word` items, not `Pair`"), "{m}");
    }

    /// The megakernel skips a sink's release fence by `sched_is_sink` (docs/scheduler.md
    /// 2.2): it must name exactly the procedures that declare no emits.
    #[test]
    fn the_sink_test_names_exactly_the_procedures_without_emits() {
        let source = |name: &str, to: &str| {
            Procedure::new(name, word(), 1).emits(to, 1).body(&format!(
                "fn {name}_execute(item: Word, inv: Invocation) {{ enqueue_{to}(item); }}"
            ))
        };
        let chain = Program::new(
            vec![source("a", "sink"), sink(), source("b", "sink")],
            UserBindings::none(),
        )
        .unwrap();
        assert!(
            chain
                .tables_wgsl(true)
                .contains("fn sched_is_sink(q: u32) -> bool { return q == 1u; }")
        );
        let cycle = Program::new(
            vec![source("a", "b"), source("b", "a")],
            UserBindings::none(),
        )
        .unwrap();
        assert!(
            cycle
                .tables_wgsl(true)
                .contains("fn sched_is_sink(q: u32) -> bool { return false; }")
        );
    }

    #[test]
    fn a_procedure_running_another_s_function_declares_what_it_enqueues() {
        let one = Procedure::new("one", word(), 1)
            .emits("sink", 1)
            .body("fn one_execute(item: Word, inv: Invocation) { enqueue_sink(item); }");
        let two = Procedure::new("two", word(), 1).execute_of("one");
        let m = error(vec![one, sink(), two], UserBindings::none());
        assert!(
            m.contains("procedure `two` enqueues to `sink` (one_execute -> enqueue_sink)"),
            "{m}"
        );
    }

    /// `reserve_<t>` is an enqueue to `t` like `enqueue_<t>`: it needs the declaration too.
    #[test]
    fn reserving_a_slot_of_an_undeclared_target_is_reported() {
        let one = Procedure::new("one", word(), 1).body(
            "fn one_execute(item: Word, inv: Invocation) {\n    \
             let s = reserve_sink();\n    store_word(s, Word_v_word, item.v);\n}",
        );
        let m = error(vec![one, sink()], UserBindings::none());
        assert!(
            m.contains("procedure `one` enqueues to `sink` (one_execute -> reserve_sink)"),
            "{m}"
        );
        let declared = Procedure::new("one", word(), 1).emits("sink", 1).body(
            "fn one_execute(item: Word, inv: Invocation) {\n    \
             let s = reserve_sink();\n    store_word(s, Word_v_word, item.v);\n}",
        );
        Program::new(vec![declared, sink()], UserBindings::none()).unwrap();
    }

    /// A value other than a `u32` given to `store_word` is naga's type error plus a hint.
    #[test]
    fn a_float_given_to_store_word_is_reported_with_the_bitcast() {
        let one = Procedure::new("one", word(), 1).emits("sink", 1).body(
            "fn one_execute(item: Word, inv: Invocation) {\n    \
             let s = reserve_sink();\n    let w = 1.5;\n    store_word(s, Word_v_word, w);\n}",
        );
        let m = error(vec![one, sink()], UserBindings::none());
        assert!(m.contains("body line 4"), "{m}");
        assert!(m.contains("bitcast<u32>"), "{m}");
    }

    #[test]
    fn a_misspelt_execute_function_is_reported_by_procedure() {
        let src = Procedure::new("source", word(), 1)
            .emits("sink", 1)
            .body("fn sorce_execute(item: Word, inv: Invocation) { enqueue_sink(item); }");
        let m = error(vec![src, sink()], UserBindings::none());
        assert!(m.contains("procedure `source`"), "{m}");
        assert!(m.contains("source_execute"), "{m}");
        assert!(m.contains("defines sorce_execute"), "{m}");
    }

    #[test]
    fn an_execute_function_with_the_wrong_signature_is_rejected() {
        let src = Procedure::new("source", word(), 1).body("fn source_execute(item: Word) {}");
        let m = error(vec![src], UserBindings::none());
        assert!(m.contains("procedure `source`"), "{m}");
        assert!(m.contains("takes (Word)"), "{m}");
        assert!(m.contains("body line 1"), "{m}");
    }

    #[test]
    fn a_body_syntax_error_names_the_procedure_and_its_own_line() {
        // The error is on the body's third line, after other procedures and user WGSL that
        // put it far down the combined source.
        let body = "fn sink_execute(item: Word, inv: Invocation) {\n    \
                    let a = item.v;\n    \
                    let b = a + ;\n}";
        let user = UserBindings::storage(
            "@group(1) @binding(0) var<storage, read_write> out: array<u32>;\n\
             fn helper(x: u32) -> u32 {\n    return x;\n}",
            &[(0, false)],
        );
        let src = Procedure::new("source", word(), 1)
            .emits("sink", 1)
            .body("fn source_execute(item: Word, inv: Invocation) {\n    enqueue_sink(item);\n}");
        let m = error(
            vec![src, Procedure::new("sink", word(), 1).body(body)],
            user,
        );
        assert!(
            m.starts_with("procedure `sink`, body line 3, column"),
            "{m}"
        );
        assert!(m.contains("let b = a + ;"), "{m}");
    }

    #[test]
    fn an_unclosed_brace_is_reported_in_its_own_body() {
        // naga stumbles only at the next body's `fn`; the report must name `a`'s `{` (the
        // `}` in the comment does not count).
        let a = Procedure::new("a", word(), 1)
            .body("fn a_execute(item: Word, inv: Invocation) {\n    let x = 1u; // }\n");
        let m = error(vec![a, sink()], UserBindings::none());
        assert!(
            m.starts_with("procedure `a`, body line 1, column 43: this `{` is not closed"),
            "{m}"
        );
        assert!(m.contains("naga's error"), "{m}");
    }

    #[test]
    fn an_unknown_enqueue_is_reported_at_its_body_line() {
        let src = Procedure::new("source", word(), 1).body(
            "fn source_execute(item: Word, inv: Invocation) {\n    enqueue_nowhere(item);\n}",
        );
        let m = error(vec![src], UserBindings::none());
        assert!(
            m.starts_with("procedure `source`, body line 2, column 5"),
            "{m}"
        );
        assert!(m.contains("enqueue_nowhere"), "{m}");
    }

    #[test]
    fn a_validation_error_names_the_procedure_and_its_own_line() {
        // A constant index out of bounds passes the parser and fails naga's validator.
        let body = "fn sink_execute(item: Word, inv: Invocation) {\n    \
                    var a: array<u32, 4>;\n    a[5] = item.v;\n}";
        let m = error(
            vec![Procedure::new("sink", word(), 2).body(body)],
            UserBindings::none(),
        );
        assert!(m.starts_with("procedure `sink`, body line "), "{m}");
        assert!(
            m.starts_with("procedure `sink`, body line 3, column 5"),
            "{m}"
        );
        assert!(m.contains("out of") && m.contains("a[5] = item.v;"), "{m}");
    }

    #[test]
    fn enqueueing_to_an_undeclared_target_is_rejected_even_through_a_helper() {
        // `emit_both` lives in the user WGSL; `source` declares `left` but not `right`.
        let user = UserBindings {
            wgsl: "fn emit_both(w: Word) { enqueue_left(w); enqueue_right(w); }".into(),
            layout: vec![],
        };
        let src = Procedure::new("source", word(), 1)
            .emits("left", 1)
            .body("fn source_execute(item: Word, inv: Invocation) { emit_both(item); }");
        let left = Procedure::new("left", word(), 1)
            .body("fn left_execute(item: Word, inv: Invocation) {}");
        let right = Procedure::new("right", word(), 1)
            .body("fn right_execute(item: Word, inv: Invocation) {}");
        let m = error(vec![src, left, right], user);
        assert!(m.contains("procedure `source` enqueues to `right`"), "{m}");
        assert!(
            m.contains("source_execute -> emit_both -> enqueue_right"),
            "{m}"
        );
        // Declared targets, a declared self-loop and an unused helper are fine.
        let ok = Procedure::new("source", word(), 1)
            .emits("source", 2)
            .emits("left", 1)
            .body("fn source_execute(item: Word, inv: Invocation) { if item.v > 0u { enqueue_source(item); } enqueue_left(item); }");
        let user = UserBindings {
            wgsl: "fn unused(w: Word) { enqueue_right(w); }".into(),
            layout: vec![],
        };
        let left = Procedure::new("left", word(), 1)
            .body("fn left_execute(item: Word, inv: Invocation) {}");
        let right = Procedure::new("right", word(), 1)
            .body("fn right_execute(item: Word, inv: Invocation) {}");
        Program::new(vec![ok, left, right], user).unwrap();
    }

    #[test]
    fn user_bindings_must_match_the_declarations() {
        let p = || sink();
        let decl = "@group(1) @binding(0) var<storage, read_write> out: array<u32>;";
        let m = error(vec![p()], UserBindings::storage(decl, &[(0, true)]));
        assert!(m.contains("`out`") && m.contains("read-only"), "{m}");
        let m = error(vec![p()], UserBindings::storage(decl, &[(1, false)]));
        assert!(m.contains("no entry for binding 0"), "{m}");
        let m = error(
            vec![p()],
            UserBindings::storage(
                "@group(0) @binding(0) var<storage, read> cfg: array<u32>;",
                &[(0, true)],
            ),
        );
        assert!(m.contains("@group(0)"), "{m}");
        Program::new(vec![p()], UserBindings::storage(decl, &[(0, false)])).unwrap();
    }
}
