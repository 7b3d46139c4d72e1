//! Generates the device-driven multi-pass WGSL: the program's shared code, enqueue functions
//! that append to the next round's inputs, the plan and one entry point per procedure, and
//! `shaders/multipass.wgsl`.

use crate::program::Program;

pub const TEMPLATE: &str = include_str!("../../../shaders/multipass.wgsl");

/// Entry points in pipeline order: the plan, then the procedures.
pub fn entry_points(program: &Program) -> Vec<String> {
    let mut e = vec!["mp_plan".to_string()];
    e.extend(
        program
            .procs
            .iter()
            .map(|p| format!("mp_proc_{}", p.proc.name)),
    );
    e
}

pub fn source(program: &Program) -> String {
    let mut s = program.tables_wgsl();
    s += &program.common_wgsl();
    s += &crate::wgsl::vec4_word_accessors("mp_in", "items_in");
    s += &crate::wgsl::vec4_word_accessors("mp_out", "items_out");
    s += &crate::ItemLayout::Interleaved.execute_switch(program, "mp_in");
    let mut seen = Vec::new();
    for p in &program.procs {
        if !seen.contains(&p.layout.name) {
            seen.push(p.layout.name.clone());
            s += &crate::wgsl::load_store_fns(&p.layout, "mp_out");
        }
    }
    let args = "@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wid: vec3<u32>";
    for (t, p) in program.procs.iter().enumerate() {
        s += &format!(
            "fn enqueue_{name}(item: {ty}) {{\n    if !sched_active {{ return; }}\n    \
             let at = sched_append_slot({t}u);\n    if at == 0xffffffffu {{ return; }}\n    \
             mp_out_store_{ty}(q_base({t}u) + at * WORDS[{t}u], item);\n}}\n\
             @compute @workgroup_size(256) fn mp_proc_{name}({args}) {{ run_procedure({t}u, lid, wid.x); }}\n",
            name = p.proc.name,
            ty = p.layout.name
        );
    }
    s += TEMPLATE;
    s
}
