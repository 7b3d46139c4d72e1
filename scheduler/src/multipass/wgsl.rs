//! Generates the device-driven multi-pass WGSL: the program's shared code, item accessors in
//! the run's item layout, enqueue functions that append to the next round's inputs, one entry
//! point per procedure, and `shaders/multipass.wgsl`.

use crate::item_layout::{ItemLayout, run_item};
use crate::program::Program;

pub const TEMPLATE: &str = include_str!("../../../shaders/multipass.wgsl");
/// The device-driven loop over one procedure's round inputs, instantiated per procedure and
/// once for any procedure (`rounds_source`).
const RUN: &str = include_str!("../../../shaders/multipass_run.wgsl");

/// How a round's procedures are dispatched: `groups[g]` lists the procedures (in order) of the
/// round's indirect dispatch `g`. Every procedure alone (no fused rounds), all together
/// (fused rounds), or the producers and the sinks apart (`MultipassConfig::fused_sinks_apart`).
pub type DispatchGroups = Vec<Vec<usize>>;

/// The entry point that runs dispatch group `g` of `groups`: a procedure's own, the fused
/// round's for all of them, else the group's (`mp_group_<g>`).
pub fn group_entry(program: &Program, groups: &DispatchGroups, g: usize) -> String {
    match groups[g].as_slice() {
        [q] => format!("mp_proc_{}", program.procs[*q].proc.name),
        all if all.len() == program.queue_count() => "mp_round".into(),
        _ => format!("mp_group_{g}"),
    }
}

/// Entry points in pipeline order: the plan, then the procedures, then the entry of every
/// dispatch group of several procedures (`group_entry`).
pub fn entry_points(program: &Program, groups: &DispatchGroups) -> Vec<String> {
    let mut e = vec!["mp_plan".to_string()];
    e.extend(
        program
            .procs
            .iter()
            .map(|p| format!("mp_proc_{}", p.proc.name)),
    );
    for (g, members) in groups.iter().enumerate() {
        if members.len() > 1 {
            e.push(group_entry(program, groups, g));
        }
    }
    e
}

/// The WGSL for `program` with its queues laid out as `items` (the same layout in the round
/// buffers of every queue), its rounds dispatched as `groups`.
pub fn source(program: &Program, items: ItemLayout, groups: &DispatchGroups) -> String {
    let args = "@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>";
    let mut s = rounds_source(
        program,
        items,
        "mp_proc",
        args,
        "lid, wid.x, false",
        RUN,
        true,
    );
    // Word `w` of item `at` of queue `t` (the carried inputs' copy).
    let word_at = match items {
        ItemLayout::Interleaved => "q_base(t) + at * WORDS[t] + w",
        ItemLayout::Planar => "q_base(t) + w * q_cap(t) + at",
    };
    s += &format!("fn mp_word_at(t: u32, at: u32, w: u32) -> u32 {{ return {word_at}; }}\n");
    let nq = program.queue_count();
    let mut group_of = vec![0; nq];
    for (g, members) in groups.iter().enumerate() {
        for &q in members {
            group_of[q] = g;
        }
    }
    let list = |f: &dyn Fn(usize) -> usize| {
        (0..nq)
            .map(|q| format!("{}u", f(q)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    // GROUP[q]: q's dispatch group; GROUP_LEN[q]: how many procedures share its dispatch.
    s += &format!(
        "const NG: u32 = {}u;\nconst GROUP: array<u32, {nq}> = array<u32, {nq}>({});\n\
         const GROUP_LEN: array<u32, {nq}> = array<u32, {nq}>({});\n",
        groups.len(),
        list(&|q| group_of[q]),
        list(&|q| groups[group_of[q]].len()),
    );
    s += TEMPLATE;
    // A group of several procedures, not all: a switch over their own loops.
    for (g, members) in groups.iter().enumerate() {
        if members.len() < 2 || members.len() == nq {
            continue;
        }
        let cases: String = members
            .iter()
            .map(|q| {
                format!("        case {q}u: {{ run_procedure_{q}({q}u, lid, pick.y, true); }}\n")
            })
            .collect();
        s += &format!(
            "@compute @workgroup_size(256) fn mp_group_{g}({args}) {{\n    \
             let pick = mp_pick(lid, wid.x, {g}u);\n    switch pick.x {{\n{cases}        \
             default: {{}}\n    }}\n}}\n"
        );
    }
    s
}

/// The WGSL both multi-passes share (the device-driven one above, the host-driven one in
/// `host.rs`), before their templates: the program's code, accessors of the round buffers
/// `mp_in`/`mp_out` in the layout `items`, and per procedure `t` an append-style
/// `enqueue_<name>`, `mp_execute_<t>` (runs item `at` of t's inputs through t's body alone),
/// `run`'s loop instantiated as `run_procedure_<t>`, and the entry point
/// `{entry}_<name>({args})`, which calls `run_procedure_<t>(t, {call})`. With `generic`, also
/// `mp_execute` and `run_procedure` for any procedure, by `q` (through `sched_execute`'s
/// switch). Each entry point reaches only its own procedure's code, so the driver allocates
/// registers and workgroup memory for that procedure alone (`shaders/multipass_run.wgsl`).
pub(super) fn rounds_source(
    program: &Program,
    items: ItemLayout,
    entry: &str,
    args: &str,
    call: &str,
    run: &str,
    generic: bool,
) -> String {
    let mut s = program.tables_wgsl();
    s += &program.common_wgsl();
    s += &crate::wgsl::vec4_word_accessors("mp_in", "items_in");
    s += &crate::wgsl::vec4_word_accessors("mp_out", "items_out");
    // The item loads; with `generic`, `sched_execute`'s switch too (only the generic loop
    // calls it).
    s += &if generic {
        items.execute_switch(program, "mp_in")
    } else {
        items.typed_fns(program, "mp_in")
    };
    s += &items.typed_fns(program, "mp_out");
    // Where item `at` of queue `t` starts, and (planar) the stride between its words.
    let item_at = |t: &str| match items {
        ItemLayout::Interleaved => format!("q_base({t}) + at * WORDS[{t}]"),
        ItemLayout::Planar => format!("q_base({t}) + at, q_cap({t})"),
    };
    // The loop, its item runner named `mp_execute{suffix}`, as `run_procedure{suffix}` (the
    // file's header comment, up to its first blank line, stays out of the copies).
    let run = run.split_once("\n\n").map_or(run, |(_, body)| body);
    let instantiate = |suffix: &str| {
        run.replace("RUN_PROCEDURE", &format!("run_procedure{suffix}"))
            .replace("MP_EXECUTE", &format!("mp_execute{suffix}"))
    };
    if generic {
        s += &format!(
            "fn mp_execute(t: u32, at: u32, inv: Invocation) {{ sched_execute(t, {}, inv); }}\n",
            item_at("t")
        );
        s += &instantiate("");
    }
    for (t, p) in program.procs.iter().enumerate() {
        s += &format!(
            "fn enqueue_{name}(item: {ty}) {{\n    if !sched_active {{ return; }}\n    \
             let at = sched_append_slot({t}u);\n    if at == 0xffffffffu {{ return; }}\n    \
             mp_out_store_{ty}({store_at}, item);\n}}\n\
             fn mp_execute_{t}(t: u32, at: u32, inv: Invocation) {{ {run_item} }}\n\
             @compute @workgroup_size(256) fn {entry}_{name}({args}) {{ run_procedure_{t}({t}u, {call}); }}\n",
            name = p.proc.name,
            ty = p.layout.name,
            store_at = item_at(&format!("{t}u")),
            run_item = run_item(&p.layout.name, "mp_in", &item_at("t"), &p.proc.execute_fn()),
        );
        s += &instantiate(&format!("_{t}"));
    }
    s
}
