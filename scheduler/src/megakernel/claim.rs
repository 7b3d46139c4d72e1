//! What a workgroup claims: the order it tries the queues in ([`priority_order`], from
//! [`QueuePolicy`]) and how many items one batch of each queue holds ([`batch_items`]). Both are
//! computed once per compiled megakernel and passed to the shader in its params; from the
//! batch sizes, the most one batch may emit to a queue ([`worst_batch_output`]).

use super::layout::MAX_BATCH;
use super::{MegakernelConfig, QueuePolicy};
use crate::error::RunError;
use crate::program::Program;

/// Most items one batch of each queue holds: `items_per_step` times the procedure's steps
/// (`MegakernelConfig::procedure_batch_steps`, else `batch_steps`), at most [`MAX_BATCH`].
/// Errors: a name in `procedure_batch_steps` that is no procedure of `program` (the message
/// lists the program's), a name given twice, or 0 steps.
pub(super) fn batch_items(
    program: &Program,
    config: &MegakernelConfig,
) -> Result<Vec<u32>, RunError> {
    let mut steps = vec![config.batch_steps.max(1); program.queue_count()];
    let mut named = vec![false; program.queue_count()];
    for (name, n) in &config.procedure_batch_steps {
        let q = program.index_of(name).ok_or_else(|| {
            let known: Vec<&str> = program.procs.iter().map(|p| p.proc.name.as_str()).collect();
            RunError::Program(format!(
                "batch steps name unknown procedure `{name}` (this program's: {})",
                known.join(", ")
            ))
        })?;
        if std::mem::replace(&mut named[q], true) {
            return Err(RunError::Program(format!(
                "batch steps name procedure `{name}` twice"
            )));
        }
        if *n == 0 {
            return Err(RunError::Program(format!(
                "batch steps of `{name}` must be at least 1"
            )));
        }
        steps[q] = *n;
    }
    Ok((program.procs.iter().zip(steps))
        .map(|(p, s)| (p.items_per_step * s).min(MAX_BATCH))
        .collect())
}

pub(super) fn priority_order(
    program: &Program,
    policy: &QueuePolicy,
) -> Result<Vec<u32>, RunError> {
    let nq = program.queue_count();
    let mut order = Vec::new();
    if let QueuePolicy::Priority(names) = policy {
        for n in names {
            let q = program.index_of(n).ok_or_else(|| {
                RunError::Program(format!("priority names unknown procedure `{n}`"))
            })?;
            if !order.contains(&(q as u32)) {
                order.push(q as u32);
            }
        }
    }
    for q in (0..nq as u32).rev() {
        if !order.contains(&q) {
            order.push(q);
        }
    }
    Ok(order)
}

/// The most items one batch of any queue may emit to queue `t` (`batch[q]` items of `q`, each up
/// to its declared emits to `t`): the room a running batch may hold promised in `t`'s budget.
pub(super) fn worst_batch_output(program: &Program, batch: &[u32], t: usize) -> u64 {
    (program.procs.iter().zip(batch))
        .map(|(p, &b)| b as u64 * p.emits[t] as u64)
        .max()
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ItemType, Procedure};

    fn program() -> Program {
        let item = ItemType::new("Item", "struct Item { x: u32 }");
        let a = Procedure::new("a", item.clone(), 4)
            .emits("b", 2)
            .body("fn a_execute(item: Item, inv: Invocation) { enqueue_b(item); }");
        let b = Procedure::new("b", item, 256).body("fn b_execute(item: Item, inv: Invocation) {}");
        Program::new(vec![a, b], crate::UserBindings::none()).unwrap()
    }

    #[test]
    fn batch_items_take_each_procedures_steps() {
        let p = program();
        let mut c = MegakernelConfig {
            batch_steps: 2,
            ..Default::default()
        };
        // a: 64 items a step, b: 1.
        assert_eq!(batch_items(&p, &c).unwrap(), vec![128, 2]);
        c.procedure_batch_steps = vec![("b".into(), 8)];
        assert_eq!(batch_items(&p, &c).unwrap(), vec![128, 8]);
        c.procedure_batch_steps = vec![("a".into(), 64)];
        assert_eq!(batch_items(&p, &c).unwrap()[0], MAX_BATCH);
        c.procedure_batch_steps = vec![("c".into(), 2)];
        assert!(batch_items(&p, &c).is_err());
        c.procedure_batch_steps = vec![("a".into(), 0)];
        assert!(batch_items(&p, &c).is_err());
        c.procedure_batch_steps = vec![("a".into(), 2), ("a".into(), 4)];
        assert!(batch_items(&p, &c).is_err());
    }
}
