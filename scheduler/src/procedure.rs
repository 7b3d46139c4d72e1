//! A procedure: one kind of work. It is declared once and runs unchanged under every strategy.
//!
//! The body is WGSL defining `fn <name>_execute(item: <Item>, inv: Invocation)`. It is called by
//! all `threads_per_item` threads of an item together, in uniform control flow (so it may use
//! `workgroupBarrier`), also for inactive slots at the end of a batch: `inv.live` is false there,
//! the item is zeroed, and enqueues are ignored; other side effects must check `inv.live`.
//! Work is emitted only through generated functions: `enqueue_<target>(item)`, or for an item
//! written a word at a time `reserve_<target>()` and `store_word(slot, word, value)`.

/// A queue item type: a WGSL struct declaration. Items travel through the queues as
/// `size / 4` u32 words in naga's storage layout (padding included); only 32-bit `u32`, `i32`,
/// `f32` scalars, vectors, matrices, fixed-size arrays and nested structs can travel. The host
/// twin is a `#[repr(C)]` bytemuck type; [`crate::wgsl::struct_layout`] reports the offsets to
/// check it against.
#[derive(Debug, Clone)]
pub struct ItemType {
    /// The struct's WGSL name, e.g. `TreeNode`.
    pub name: String,
    /// The declaration, e.g. `struct TreeNode { id: u32, depth: u32 }` (other declarations it
    /// needs may come along; an item type shared by several procedures is declared once).
    pub wgsl: String,
}

impl ItemType {
    /// Item type `name` declared by `wgsl`.
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
    /// The element type, e.g. `atomic<u32>` or `vec4<f32>`.
    pub wgsl_type: String,
    /// Elements per item.
    pub per_item: u32,
}

/// One kind of work: an item type, the threads that run one item together, the most items
/// one item may emit to each target, and a WGSL body.
///
/// ```
/// use scheduler::{ItemType, Procedure};
/// let node = ItemType::new("Node", "struct Node { id: u32, depth: u32 }");
/// // Four threads per item; each thread enqueues one child, so one item emits up to 4.
/// let split = Procedure::new("split", node, 4).emits("split", 4).body(
///     "fn split_execute(item: Node, inv: Invocation) {
///          if item.depth < 3u { enqueue_split(Node(item.id * 4u + inv.thread, item.depth + 1u)); }
///      }",
/// );
/// assert_eq!(split.max_emits, [("split".to_string(), 4)]);
/// ```
///
/// **The body** must define `fn <name>_execute(item: <Item>, inv: Invocation)` (in its own
/// body, another procedure's or the user WGSL; [`crate::Program::new`] checks it). It runs on
/// all `threads_per_item` threads of an item together, in workgroup-uniform control flow (so it
/// may call `workgroupBarrier`), also for padding slots: `inv.live == false` there, the item is
/// zeroed and enqueues are ignored; any other side effect must check `inv.live`.
/// `Invocation { thread, slot, live, threads }`: `thread` in `0..threads_per_item`, `slot` in
/// `0..items_per_step` with `items_per_step = 256 / threads_per_item`, `threads` the running
/// procedure's `threads_per_item` (which tells apart procedures that share an execute function,
/// [`Procedure::execute_of`]).
///
/// **Emitting work.** `enqueue_<target>(item)` appends one item to `target`'s queue *for every
/// call, by every thread*: in an item of several threads, a call made by each of them adds one
/// item each (guard with `if inv.thread == 0u` for one item per item). All strategies behave
/// alike here (megakernel, `multipass`, `multipass-host`). The declared maximum of
/// [`Procedure::emits`] counts the calls of all the item's threads together; more is a
/// [`crate::RunError::EmitLimit`] (the megakernel checks the total of a batch of items, the
/// multi-pass strategies each item). Calling `enqueue_<target>` for a target not declared with
/// `emits` is rejected by [`crate::Program::new`], also through helper functions.
///
/// **Large items a word at a time.** `let slot = reserve_<target>();` takes the slot
/// `enqueue_<target>` would fill (same rules: one per call, counted against `emits`), and
/// `store_word(slot, word, value)` writes its u32 word `word`, so a body need not hold a whole
/// child in registers (the megakernel's registers are its hungriest procedure's). Word offsets
/// of each item member come generated as `const <Item>_<member>_word: u32`; guard the stores
/// with one `if slot_reserved(slot)`; `SCHED_MEGAKERNEL` (a `bool` constant) tells a body which
/// kind of kernel it is in. docs/scheduler.md, section 1, "Large items word by word".
#[derive(Debug, Clone)]
pub struct Procedure {
    /// The procedure's name, a WGSL identifier not starting with `sched_` or `__`; its queue,
    /// enqueue function (`enqueue_<name>`) and execute function (`<name>_execute`) derive from it.
    pub name: String,
    /// The type of its items.
    pub item: ItemType,
    /// Threads that run one item together: a power of two from 1 to 256.
    pub threads_per_item: u32,
    /// Workgroup memory per item, if any ([`Procedure::shared`]).
    pub shared: Option<SharedMemory>,
    /// Worst case items emitted to each target per executed item. Both strategies reserve output
    /// space from this before running a batch, which is how no queue can overflow mid-batch.
    pub max_emits: Vec<(String, u32)>,
    /// The WGSL body ([`Procedure::body`]).
    pub body: String,
    /// The procedure whose execute function this one runs, if not its own
    /// ([`Procedure::execute_of`]).
    pub execute_of: Option<String>,
    /// Targets whose items this procedure's batches may keep in workgroup memory and run next on
    /// the same workgroup ([`Procedure::local`]).
    pub local: Vec<String>,
}

impl Procedure {
    /// A procedure `name` on items of type `item`, run by `threads_per_item` threads per item
    /// (a power of two from 1 to 256, checked by [`crate::Program::new`]), emitting nothing and
    /// with an empty body until declared.
    pub fn new(name: &str, item: ItemType, threads_per_item: u32) -> Self {
        Procedure {
            name: name.into(),
            item,
            threads_per_item,
            shared: None,
            max_emits: Vec::new(),
            body: String::new(),
            execute_of: None,
            local: Vec::new(),
        }
    }

    /// Declares that one executed item may emit up to `max` items to procedure `target`, counting
    /// the `enqueue_<target>` calls of all its threads. Repeated calls for one target add up.
    pub fn emits(mut self, target: &str, max: u32) -> Self {
        self.max_emits.push((target.into(), max));
        self
    }

    /// Lets the items this procedure emits to `target` (declared with [`Procedure::emits`]) stay
    /// with the workgroup: in the megakernel with `MegakernelConfig::local_queues` (off by
    /// default: it pays where a batch's children fill the workgroup's next steps, such as trees
    /// that do not die out, and costs where a few pieces are left before other work, as on Reyes'
    /// patches; docs/scheduler.md 2.7), a batch's
    /// emits to `target` go to the workgroup's own area of the slots buffer while it has room, and
    /// the workgroup runs them as its next batch, without the global queue's tickets, flags and
    /// claim (Whippletree's per-block queues, Steinberger et al. 2014, section 4; the local
    /// bound-and-split of Micropolis, Weber et al. 2015). What does
    /// not fit goes to the global queue as before. While another workgroup of the launch is idle,
    /// a workgroup keeps only one step's worth (`items_per_step` of `target`) and shares the rest.
    /// The multi-pass strategies have no workgroup that outlives a pass and ignore it. Checked by
    /// [`crate::Program::new`]: `target` must be one this procedure emits to.
    pub fn local(mut self, target: &str) -> Self {
        self.local.push(target.into());
        self
    }

    /// Declares workgroup memory `var<workgroup> <name>_shared: array<wgsl_type, per_item *
    /// items_per_step>`; item `inv.slot` owns elements `[slot * per_item, (slot + 1) * per_item)`.
    /// The megakernel holds every procedure's array at once, so the sum counts against the
    /// device's workgroup memory limit.
    pub fn shared(mut self, wgsl_type: &str, per_item: u32) -> Self {
        self.shared = Some(SharedMemory {
            wgsl_type: wgsl_type.into(),
            per_item,
        });
        self
    }

    /// Sets the WGSL body: `fn <name>_execute(item: <Item>, inv: Invocation)` and any helpers
    /// (helper names share one module with every other body and the scheduler's code: prefix
    /// them, e.g. with the procedure name).
    pub fn body(mut self, wgsl: &str) -> Self {
        self.body = wgsl.into();
        self
    }

    /// Runs procedure `other`'s execute function, `<other>_execute`, instead of one of its own
    /// (which it then need not define): `other` is declared in the same program, has the same
    /// item type and runs its own function; `inv.threads` tells the two apart. The megakernel
    /// calls a function shared so from one place for all its procedures, so that a compiler that
    /// inlines every call (lavapipe, turning SPIR-V into NIR) compiles its code once, not once
    /// per procedure. Checked by [`crate::Program::new`].
    pub fn execute_of(mut self, other: &str) -> Self {
        self.execute_of = Some(other.into());
        self
    }

    /// The name of the WGSL function that runs its items: `<name>_execute`, or
    /// `<other>_execute` with [`Procedure::execute_of`].
    pub fn execute_fn(&self) -> String {
        format!(
            "{}_execute",
            self.execute_of.as_deref().unwrap_or(&self.name)
        )
    }
}
