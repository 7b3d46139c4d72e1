//! A procedure: one kind of work. It is declared once and runs unchanged under every strategy.
//!
//! The body is WGSL defining `fn <name>_execute(item: <Item>, inv: Invocation)`. It is called by
//! all `threads_per_item` threads of an item together, in uniform control flow (so it may use
//! `workgroupBarrier`), also for inactive slots at the end of a batch: `inv.live` is false there,
//! the item is zeroed, and enqueues are ignored; other side effects must check `inv.live`.
//! Work is emitted only through generated functions `enqueue_<target>(item)`.

/// A queue item type: a WGSL struct declaration (the host twin is a `#[repr(C)]` bytemuck type;
/// see [`crate::wgsl::struct_layout`] for checking that they agree).
#[derive(Debug, Clone)]
pub struct ItemType {
    pub name: String,
    pub wgsl: String,
}

impl ItemType {
    pub fn new(name: &str, wgsl: &str) -> Self {
        ItemType {
            name: name.into(),
            wgsl: wgsl.into(),
        }
    }
}

/// Workgroup memory a procedure gets per item in flight: `<name>_shared`, an array of
/// `per_item * items_per_step` elements of `wgsl_type`; item `inv.slot` owns elements
/// `[inv.slot * per_item, (inv.slot + 1) * per_item)`.
#[derive(Debug, Clone)]
pub struct SharedMemory {
    pub wgsl_type: String,
    pub per_item: u32,
}

#[derive(Debug, Clone)]
pub struct Procedure {
    pub name: String,
    pub item: ItemType,
    /// Threads that run one item together: a power of two from 1 to 256.
    pub threads_per_item: u32,
    pub shared: Option<SharedMemory>,
    /// Worst case items emitted to each target per executed item. Both strategies reserve output
    /// space from this before running a batch, which is how no queue can overflow mid-batch.
    pub max_emits: Vec<(String, u32)>,
    pub body: String,
}

impl Procedure {
    pub fn new(name: &str, item: ItemType, threads_per_item: u32) -> Self {
        Procedure {
            name: name.into(),
            item,
            threads_per_item,
            shared: None,
            max_emits: Vec::new(),
            body: String::new(),
        }
    }

    /// Declares that one item may emit up to `max` items to procedure `target`.
    pub fn emits(mut self, target: &str, max: u32) -> Self {
        self.max_emits.push((target.into(), max));
        self
    }

    pub fn shared(mut self, wgsl_type: &str, per_item: u32) -> Self {
        self.shared = Some(SharedMemory {
            wgsl_type: wgsl_type.into(),
            per_item,
        });
        self
    }

    pub fn body(mut self, wgsl: &str) -> Self {
        self.body = wgsl.into();
        self
    }
}
