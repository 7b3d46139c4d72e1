//! A program: procedures registered together, validated, with the WGSL both strategies share
//! (item structs, bodies, user declarations, the procedure tables). Each strategy adds its own
//! enqueue functions and driver loop around this.

use crate::bindings::UserBindings;
use crate::error::RunError;
use crate::procedure::Procedure;
use crate::wgsl::{self, StructLayout};

mod validation;

/// Where a piece of the program's shared WGSL came from ([`Program::common_parts`]), so that
/// an error in it can name what the user wrote.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Part {
    /// Written by the scheduler (`Invocation`; the enqueue stubs of validation).
    Generated,
    /// An item struct's declaration, by struct name.
    Item(String),
    /// The workgroup array `.shared(...)` declares for procedure `i`.
    Shared(usize),
    /// [`crate::UserBindings::wgsl`].
    User,
    /// The body of procedure `i`.
    Body(usize),
}

/// Workgroup size of every scheduler kernel but a megakernel given another
/// (`MegakernelConfig::workgroup_size`, [`Program::with_workgroup_size`]); threads per item
/// divide it.
pub const WORKGROUP_SIZE: u32 = 256;

/// A procedure after validation: its declaration, item layout and resolved emit table. Its
/// index in [`Program::procs`] is its queue index.
#[derive(Debug, Clone)]
pub struct ProcInfo {
    /// The procedure as declared.
    pub proc: Procedure,
    /// Its item struct's layout as naga computes it (size, offsets, every scalar).
    pub layout: StructLayout,
    /// Items one workgroup step runs: [`Program::workgroup_size`] / `threads_per_item`.
    pub items_per_step: u32,
    /// `emits[t]`: worst-case items emitted to queue `t` per executed item.
    pub emits: Vec<u32>,
    /// `local[t]`: items emitted to queue `t` may stay in the workgroup ([`Procedure::local`]).
    pub local: Vec<bool>,
}

impl ProcInfo {
    /// Words (u32) per item in a queue: the item struct's size / 4.
    pub fn words(&self) -> u32 {
        self.layout.words()
    }

    /// It emits nothing (a sink: Reyes' DiceShade, the tree's leaves).
    pub fn is_sink(&self) -> bool {
        self.emits.iter().all(|&e| e == 0)
    }
}

/// Procedures registered together and validated, with the user's bind group 1: what every
/// strategy compiles ([`crate::Scheduler::new`]). Cloning is cheap enough to keep one per
/// scheduler.
#[derive(Debug, Clone)]
pub struct Program {
    /// The procedures in registration order; a procedure's index is its queue index (the order
    /// of [`crate::RunStats::executed`]).
    pub procs: Vec<ProcInfo>,
    /// The user's resources (bind group 1).
    pub user: UserBindings,
    /// Performance notes on the bodies, found by [`Program::new`] (see [`Program::notes`]).
    notes: Vec<String>,
    /// Threads per workgroup of the kernels compiled from this program: [`WORKGROUP_SIZE`]
    /// unless [`Program::with_workgroup_size`] says otherwise.
    workgroup_size: u32,
}

impl Program {
    /// Registers and validates `procedures` with the user resources `user`.
    ///
    /// Checks: at least one procedure; names are WGSL identifiers not starting with `sched_` or
    /// `__`, without duplicates; threads per item a power of two from 1 to 256; `emits` targets
    /// are procedures; item structs can travel in a queue (see [`ItemType`](crate::ItemType));
    /// item structs, user WGSL and bodies compile together with stub `enqueue_*` functions;
    /// every `<name>_execute(item: <Item>, inv: Invocation)` exists (but for a procedure that
    /// runs another's, [`Procedure::execute_of`]: that one exists and has the same item type,
    /// and itself runs its own); no procedure calls
    /// `enqueue_<t>` (directly or through helpers) for a target it did not declare with
    /// [`Procedure::emits`]; every `@group(1)` variable has a layout entry of the same binding
    /// and storage access; naga's SPIR-V backend, which wgpu runs when a strategy makes its
    /// pipeline, writes every execute function (it panics on some code its validator accepts).
    ///
    /// Errors: [`RunError::Program`]. A WGSL error names where it is: the procedure and the
    /// line and column within its body (or the user WGSL, or the item struct), with the line.
    /// A failure of the SPIR-V backend names the procedure only (the backend gives no line);
    /// its panic is caught (not under `panic = "abort"`), but the default panic hook prints
    /// naga's message first.
    /// User WGSL must also avoid the identifiers of the scheduler's generated code (`ctrl`,
    /// `slots`, `NQ`, `Q_*`, `wg_*`, `mp_*`, ...); a clash there is reported by the strategy's
    /// constructor.
    pub fn new(procedures: Vec<Procedure>, user: UserBindings) -> Result<Program, RunError> {
        if procedures.is_empty() {
            return Err(RunError::Program(
                "a program needs at least one procedure".into(),
            ));
        }
        let index = |name: &str| procedures.iter().position(|p| p.name == name);
        let mut procs = Vec::new();
        for (i, p) in procedures.iter().enumerate() {
            if !is_identifier(&p.name) {
                return Err(RunError::Program(format!(
                    "`{}` is not a WGSL identifier",
                    p.name
                )));
            }
            if index(&p.name) != Some(i) {
                return Err(RunError::Program(format!(
                    "procedure `{}` registered twice",
                    p.name
                )));
            }
            let t = p.threads_per_item;
            if !t.is_power_of_two() || t > WORKGROUP_SIZE {
                return Err(RunError::Program(format!(
                    "procedure `{}`: threads per item must be a power of two from 1 to {WORKGROUP_SIZE}, got {t}",
                    p.name
                )));
            }
            let mut emits = vec![0; procedures.len()];
            for (target, max) in &p.max_emits {
                let ti = index(target).ok_or_else(|| {
                    RunError::Program(format!(
                        "procedure `{}` emits to unknown `{target}`",
                        p.name
                    ))
                })?;
                emits[ti] += max;
            }
            let mut local = vec![false; procedures.len()];
            for target in &p.local {
                match index(target) {
                    Some(ti) if emits[ti] > 0 => local[ti] = true,
                    _ => {
                        return Err(RunError::Program(format!(
                            "procedure `{}` keeps its `{target}` items local, but does not emit \
                             to `{target}` (declare it with `emits`)",
                            p.name
                        )));
                    }
                }
            }
            if let Some(other) = &p.execute_of {
                let o = index(other).map(|o| &procedures[o]).ok_or_else(|| {
                    RunError::Program(format!(
                        "procedure `{}` runs the execute function of unknown `{other}`",
                        p.name
                    ))
                })?;
                if o.execute_of.is_some() {
                    return Err(RunError::Program(format!(
                        "procedure `{}` runs `{other}_execute`, but `{other}` itself runs \
                         another's: name the procedure that runs its own",
                        p.name
                    )));
                }
                if o.item.name != p.item.name {
                    return Err(RunError::Program(format!(
                        "procedure `{}` runs `{other}_execute`, which takes `{}` items, not `{}`",
                        p.name, o.item.name, p.item.name
                    )));
                }
            }
            let layout = wgsl::struct_layout(&p.item.wgsl, &p.item.name)?;
            if layout.words() == 0 {
                return Err(RunError::Program(format!(
                    "item `{}` is empty",
                    p.item.name
                )));
            }
            procs.push(ProcInfo {
                proc: p.clone(),
                layout,
                items_per_step: WORKGROUP_SIZE / t,
                emits,
                local,
            });
        }
        let mut program = Program {
            procs,
            user,
            notes: Vec::new(),
            workgroup_size: WORKGROUP_SIZE,
        };
        // Compile the shared part once on its own, so that an error names the procedure and a
        // line of its body, not a line of a strategy's generated shader; then check what naga
        // parsed: every `<name>_execute`, enqueue targets against `.emits`, user bindings.
        program.notes = validation::check(&program)?;
        for n in &program.notes {
            log::warn!("{n}");
        }
        Ok(program)
    }

    /// What [`Program::new`] found slow in the bodies and user WGSL, one note each, also logged
    /// as warnings through `log` (visible only with a logger at warn level: env_logger shows
    /// errors only unless told, e.g. `RUST_LOG=warn`): today, a run-time index into an array
    /// or matrix of a parameter (the `item` of an execute function, or a helper's). naga's SPIR-V output copies the whole array to a temporary at
    /// every such access (a value cannot be indexed dynamically in SPIR-V); copy the item
    /// into a `var` once and index that (docs/scheduler.md, "Writing fast procedures").
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// Whether some procedure keeps some of its emits local ([`Procedure::local`]).
    pub fn has_local(&self) -> bool {
        self.procs.iter().any(|p| p.local.iter().any(|&l| l))
    }

    /// Threads per workgroup of the kernels compiled from this program (default
    /// [`WORKGROUP_SIZE`]).
    pub fn workgroup_size(&self) -> u32 {
        self.workgroup_size
    }

    /// This program for kernels of `size` threads per workgroup: every procedure's
    /// `items_per_step` and `.shared` array scale with it. Errors: a size that is not a
    /// multiple of [`WORKGROUP_SIZE`] (every procedure's threads per item must divide it, and
    /// the scheduler's own lanes 253-255 must exist) or above 1,024.
    pub fn with_workgroup_size(&self, size: u32) -> Result<Program, RunError> {
        if size == 0 || !size.is_multiple_of(WORKGROUP_SIZE) || size > 1024 {
            return Err(RunError::Program(format!(
                "workgroup size must be a multiple of {WORKGROUP_SIZE} up to 1024, got {size}"
            )));
        }
        let mut p = self.clone();
        p.workgroup_size = size;
        for info in &mut p.procs {
            info.items_per_step = size / info.proc.threads_per_item;
        }
        Ok(p)
    }

    /// Number of procedures, which is the number of queues.
    pub fn queue_count(&self) -> usize {
        self.procs.len()
    }

    /// The queue index of procedure `name`, if registered.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.procs.iter().position(|p| p.proc.name == name)
    }

    /// WGSL common to both strategies: `Invocation`, item structs, per-procedure workgroup
    /// memory, user declarations and the bodies, in that order.
    pub(crate) fn common_wgsl(&self) -> String {
        self.common_parts()
            .into_iter()
            .map(|(_, text)| text + "\n")
            .collect()
    }

    /// [`Program::common_wgsl`] in parts, each with where it came from (for error reports).
    pub(crate) fn common_parts(&self) -> Vec<(Part, String)> {
        let mut parts = vec![(
            Part::Generated,
            "struct Invocation {\n    // thread within the item, 0..threads_per_item\n    thread: u32,\n    \
             // item slot within the workgroup step, 0..items_per_step\n    slot: u32,\n    \
             // false for padding slots at the end of a batch\n    live: bool,\n    \
             // threads per item of the running procedure\n    threads: u32,\n}\n\
             // An item's slot taken by `reserve_<name>()`, filled word by word with `store_word`\n\
             // (word k at `at + k * stride`; `at` 0xffffffff: dropped; `outbox`: in the outbox)\n\
             struct ItemSlot {\n    at: u32,\n    stride: u32,\n    outbox: u32,\n}\n\
             // Whether `reserve_<name>()` took a slot (false: its item is dropped)\n\
             fn slot_reserved(slot: ItemSlot) -> bool { return slot.at != 0xffffffffu; }"
                .to_string(),
        )];
        let mut seen = Vec::new();
        for p in &self.procs {
            if !seen.contains(&p.layout.name) {
                seen.push(p.layout.name.clone());
                parts.push((Part::Item(p.layout.name.clone()), p.proc.item.wgsl.clone()));
                // Where each member starts, in words, for `store_word`.
                let consts: String = (p.layout.members.iter())
                    .map(|(m, byte)| {
                        format!("const {}_{m}_word: u32 = {}u;\n", p.layout.name, byte / 4)
                    })
                    .collect();
                parts.push((Part::Generated, consts));
            }
        }
        for (i, p) in self.procs.iter().enumerate() {
            if let Some(sh) = &p.proc.shared {
                parts.push((
                    Part::Shared(i),
                    format!(
                        "var<workgroup> {}_shared: array<{}, {}>;",
                        p.proc.name,
                        sh.wgsl_type,
                        sh.per_item * p.items_per_step
                    ),
                ));
            }
        }
        parts.push((Part::User, self.user.wgsl.clone()));
        for (i, p) in self.procs.iter().enumerate() {
            parts.push((Part::Body(i), p.proc.body.clone()));
        }
        parts
    }

    /// Constant tables: the queue count, then threads per item, item words and the emit table.
    /// Item words and emits are functions of selects in every strategy
    /// ([`crate::wgsl::table_fn`]: `sched_words`, `sched_emits`): naga writes a run-time index
    /// into a `const` array as a store of the whole array to a function variable and a load,
    /// and the functions took 2-5% off the device-driven multi-pass on the H100 and 2.8-2.9%
    /// off the megakernel's frames. Threads per item: `megakernel: false` (both multi-passes)
    /// the function `sched_threads`; `megakernel: true` a `const` array, `THREADS`, with the
    /// sink test `sched_is_sink`: as a function it made the megakernel's 64-root trees with
    /// local queues 1.6-3.6x slower on the H100 (its bisection: docs/results.md, 2026-12-05
    /// (ninth session)).
    pub(crate) fn tables_wgsl(&self, megakernel: bool) -> String {
        use crate::wgsl::table_fn;
        let nq = self.procs.len();
        let threads: Vec<u32> = self.procs.iter().map(|p| p.proc.threads_per_item).collect();
        let words: Vec<u32> = self.procs.iter().map(|p| p.words()).collect();
        let emits: Vec<u32> = self.procs.iter().flat_map(|p| p.emits.clone()).collect();
        let threads_fn = match megakernel {
            true => String::new(),
            false => table_fn("sched_threads", &threads),
        };
        let mut s = format!(
            "// Whether the bodies run in the megakernel (true) or a multi-pass kernel (false)\n\
             const SCHED_MEGAKERNEL: bool = {megakernel};\n\
             const NQ: u32 = {nq}u;\n\
             {threads_fn}{}\
             // sched_emits(q * NQ + t): worst-case items procedure q emits to queue t per item\n\
             {}",
            table_fn("sched_words", &words),
            table_fn("sched_emits", &emits),
        );
        if !megakernel {
            return s;
        }
        let list = (threads.iter())
            .map(|x| format!("{x}u"))
            .collect::<Vec<_>>()
            .join(", ");
        let sinks: Vec<String> = (0..nq)
            .filter(|&q| self.procs[q].is_sink())
            .map(|q| format!("q == {q}u"))
            .collect();
        let sinks = if sinks.is_empty() {
            "false".to_string()
        } else {
            sinks.join(" || ")
        };
        s += &format!(
            "const THREADS: array<u32, {nq}> = array<u32, {nq}>({list});\n\
             // Whether procedure q emits nothing: comparisons, not a table indexed at run time\n\
             fn sched_is_sink(q: u32) -> bool {{ return {sinks}; }}\n"
        );
        s
    }
}

/// Test fixture: `source` (`threads` threads per item, up to `emits` items to `sink`) and
/// `sink`, which emits nothing, over one-word items.
#[cfg(test)]
pub(crate) fn source_to_sink(threads: u32, emits: u32) -> Program {
    let word = crate::ItemType::new("Word", "struct Word { v: u32 }");
    let source = Procedure::new("source", word.clone(), threads)
        .emits("sink", emits)
        .body("fn source_execute(item: Word, inv: Invocation) { enqueue_sink(item); }");
    let sink =
        Procedure::new("sink", word, 1).body("fn sink_execute(item: Word, inv: Invocation) {}");
    Program::new(vec![source, sink], UserBindings::none()).unwrap()
}

fn is_identifier(s: &str) -> bool {
    let mut c = s.chars();
    matches!(c.next(), Some(ch) if ch.is_ascii_alphabetic() || ch == '_')
        && c.all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
        && !s.starts_with("sched_")
        && !s.starts_with("__")
}

/// Initial work: raw item words for one queue, by procedure name. Seeds of the same procedure
/// are concatenated; a seed for an unknown procedure, or whose word count is not a multiple of
/// the item's words, is a [`RunError::Program`] of the run.
#[derive(Debug, Clone)]
pub struct Seed {
    /// The procedure whose queue the items start in.
    pub procedure: String,
    /// Items packed back to back, `words` per item, as the `#[repr(C)]` host twin lays them out.
    pub words: Vec<u32>,
}

impl Seed {
    /// Items of `procedure` from their `#[repr(C)]` host twins (`T` must have the item
    /// struct's size and layout; check it with [`crate::wgsl::struct_layout`]).
    pub fn new<T: bytemuck::Pod>(procedure: &str, items: &[T]) -> Self {
        Seed {
            procedure: procedure.into(),
            words: bytemuck::cast_slice(items).to_vec(),
        }
    }
}
