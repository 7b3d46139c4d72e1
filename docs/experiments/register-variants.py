#!/usr/bin/env python3
"""Variants of a dumped Reyes megakernel for pipestats (docs/results.md, 2026-12-03 (third
session), "What sets the registers").

    SCHED_DUMP_WGSL=DUMP reyes render killeroo.rib --width 1920 --height 1080 --strategy megakernel
    python3 docs/experiments/register-variants.py DUMP/megakernel.wgsl OUT/
    pipestats OUT/*.wgsl            # on the GPU whose driver is asked (not lavapipe)

Each variant is a text edit of the dump; they compile but do not render (calls are removed):
  only_bound, only_split, only_dice, none   procedures' calls left in sched_execute's switch
  minimal_X / noloop_X                      procedure X alone in a minimal persistent loop
                                            (one atomic claim, the step loop, the flags) / in
                                            one call with no loop
  dice_nostats, dice_nopause, dice_noearly, dice_all3, full_all3
                                            DiceShade alone (or all) without the statistics'
                                            registers, the idle pause, the early probe, or all three
  dice_params_rw, full_params_rw, full_frame_rw
                                            `params` (and the frame's buffer) declared read_write,
                                            so that no load of them is hoisted out of the loop
  bound_nocrack, bound_noscreencrack, bound_nonear, bound_noback, bound_nocrack_nonear
                                            minimal_bound without parts of Bound's decision
  bound_zerochild                           minimal_bound, its children's nets not rebuilt
An edit that no longer matches the dump (the shaders changed) stops the script with its text.
The edits match dumps of main from 480d655 (Bound's net in workgroup memory; the third
session's figures came from fc7ad12, whose Bound called crack_dilation(&cp, &w, ...)).
"""
import os
import sys

src = open(sys.argv[1]).read()
out = sys.argv[2]
os.makedirs(out, exist_ok=True)


def must(s, a, b):
    if a not in s:
        sys.exit("register-variants: not in the dump: " + a[:80])
    return s.replace(a, b)


def drop_calls(s, names):
    for n in names:
        s = must(s, " %s(it, inv); }" % n, " }")
    return s


ALL = ["bound_execute", "splitu_execute", "splitv_execute", "diceshade_execute"]
only = {
    "bound": drop_calls(src, ["splitu_execute", "splitv_execute", "diceshade_execute"]),
    "split": drop_calls(src, ["bound_execute", "diceshade_execute"]),
    "dice": drop_calls(src, ["bound_execute", "splitu_execute", "splitv_execute"]),
}
V = {"full": src, "none": drop_calls(src, ALL)}
for k, v in only.items():
    V["only_" + k] = v

ENTRY = ("@compute @workgroup_size(256)\nfn megakernel(@builtin(local_invocation_index) lid: u32,"
         " @builtin(workgroup_id) wid: vec3<u32>) {\n")
QUEUE = {"bound": "0u", "split": "1u", "dice": "3u"}
NOLOOP = """    let q = params[P_POLICY] + {q};
    let per_step = 256u / THREADS[q];
    let slot = lid / THREADS[q];
    sched_proc = q; sched_batch_n = 4u;
    sched_active = true;
    mk_execute(q, wid.x * per_step + slot, Invocation(lid % THREADS[q], slot, sched_active, THREADS[q]));
}}
"""
MINIMAL = """    for (var iter = 0u; iter < params[P_MAX_ITERS]; iter++) {{
        if lid == 0u {{ wg_q = {q} + params[P_POLICY]; wg_n = atomicAdd(&ctrl[0], 1u) % 64u; wg_h = atomicAdd(&ctrl[32], 64u); }}
        let q = workgroupUniformLoad(&wg_q);
        let h = workgroupUniformLoad(&wg_h);
        let n = workgroupUniformLoad(&wg_n);
        if n == 63u {{ break; }}
        let per_step = 256u / THREADS[q];
        let slot = lid / THREADS[q];
        sched_proc = q;
        sched_batch_n = n;
        for (var first = 0u; first < n; first += per_step) {{
            let idx = first + slot;
            sched_active = idx < n;
            mk_execute(q, h + idx, Invocation(lid % THREADS[q], slot, sched_active, THREADS[q]));
            workgroupBarrier();
        }}
        storageBarrier();
        for (var j = lid; j < n; j += 256u) {{ atomicStore(&flags[h + j], 1u); }}
        workgroupBarrier();
    }}
}}
"""
for k, v in only.items():
    head = v[: v.index(ENTRY)]
    V["noloop_" + k] = head + ENTRY + NOLOOP.format(q=QUEUE[k])
    V["minimal_" + k] = head + ENTRY + MINIMAL.format(q=QUEUE[k])


def nostats(s):
    s = must(s, "                fold_peak();\n                st_peak_end = end;\n"
                "                st_peak_head = atomicLoad(&ctrl[t * QSTRIDE + Q_HEAD]);\n", "")
    return must(s, "                if from_local { st_local += n; } else { st_executed += n - abandoned; }\n"
                   "                st_batches += 1u;\n", "")


def nopause(s):
    return must(s, "            if lid < 32u { idle_pause(jitter(streak, wid.x, iter)); }", "")


def noearly(s):
    return must(s, "        let early = probe_load(lid);", "        let early = 0u;")


V["dice_nostats"] = nostats(only["dice"])
V["dice_nopause"] = nopause(only["dice"])
V["dice_noearly"] = noearly(only["dice"])
V["dice_all3"] = noearly(nopause(nostats(only["dice"])))
V["full_all3"] = noearly(nopause(nostats(src)))
PARAMS = "@group(0) @binding(4) var<storage, read> params: array<u32>;"
FRAME = "@group(1) @binding(0) var<storage, read> frame: Frame;"
rw = lambda d: d.replace("var<storage, read>", "var<storage, read_write>")
V["dice_params_rw"] = must(only["dice"], PARAMS, rw(PARAMS))
V["full_params_rw"] = must(src, PARAMS, rw(PARAMS))
V["full_frame_rw"] = must(V["full_params_rw"], FRAME, rw(FRAME))
mb = V["minimal_bound"]
CRACK = "        g.dilate = crack_dilation(base, rational, d.y, d.z, zmin);"
SCREEN = "            g.dilate = packed_min(g.dilate, screen_crack_dilation(base, rational, d.y, d.z));"
CHILD = "    c.cp = cp;\n    return c;"
NEAR = "    if zmin < frame.near {"
NEVER = "    if zmin < frame.near && frame.width == 77777u {"
V["bound_nocrack"] = must(must(mb, CRACK, "        g.dilate = 0u;"), SCREEN, "")
V["bound_noscreencrack"] = must(mb, SCREEN, "")
V["bound_nonear"] = must(mb, NEAR, NEVER)
V["bound_noback"] = must(mb, "    if one_sided { back = backfacing_terms(&cp, t, (info.flags & 1u) != 0u); }", "")
V["bound_nocrack_nonear"] = must(V["bound_nocrack"], NEAR, NEVER)
# The children's net written as zeros instead of rebuilt from workgroup memory (bound_child).
V["bound_zerochild"] = must(mb, CHILD, "    c.cp = array<f32, 48>();\n    return c;")
for k, v in V.items():
    open(os.path.join(out, k + ".wgsl"), "w").write(v)
print("register-variants: %d files in %s" % (len(V), out))
