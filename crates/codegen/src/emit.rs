//! Machine code for a [`Tape`], through Cranelift: one function per tape,
//! straight-line code with the constants in the instructions in the order of
//! [`Tape::schedule`], then a branch out at each guard, and the outputs
//! stored only once every guard has held (a function that gives up has
//! written nothing).
//!
//! The functions have the C signature
//! `u32 f(double *x, double *dx, const double *inputs, double step)`
//! and return 0 when they stored their outputs, 1 when a guard failed.

use cranelift_codegen::ir::condcodes::FloatCC;
use cranelift_codegen::ir::{
    AbiParam, Block, FuncRef, InstBuilder, MemFlagsData, Signature, Value, types,
};
use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{FuncId, Linkage, Module, default_libcall_names};

use super::calls::{Call1, Call2};
use super::tape::{Guard, Holds, Node, Output, Slot, Tape};

/// This build generates code.
pub(crate) const AVAILABLE: bool = true;

/// A compiled function: see the module documentation.
pub(crate) type KernelFn = unsafe extern "C" fn(*mut f64, *mut f64, *const f64, f64) -> u32;

/// A code generator for the host, with the library functions tapes call.
pub(crate) struct Generator {
    module: JITModule,
}

/// Compiled code and the module that owns it; the code is freed on drop.
pub(crate) struct Code {
    module: Option<JITModule>,
}

// SAFETY: after `finalize_definitions` the module's memory holds finished,
// read-only code that any thread may run; the module is only touched again
// to free that memory, on drop, through `&mut self`.
unsafe impl Send for Code {}
// SAFETY: as for `Send`: shared access only runs the finished code.
unsafe impl Sync for Code {}

impl Drop for Code {
    fn drop(&mut self) {
        if let Some(module) = self.module.take() {
            // SAFETY: the function pointers into this memory live in the
            // same owner (`NativeRhs`) and are dropped with it.
            unsafe { module.free_memory() };
        }
    }
}

impl Generator {
    /// A generator for the machine this runs on.
    pub(crate) fn host() -> Result<Self, String> {
        let mut flags = settings::builder();
        for (name, value) in [("opt_level", "speed"), ("enable_verifier", "false")] {
            flags.set(name, value).map_err(|e| e.to_string())?;
        }
        let isa = cranelift_native::builder()
            .map_err(|e| format!("no code generator for this machine: {e}"))?
            .finish(settings::Flags::new(flags))
            .map_err(|e| e.to_string())?;
        let mut builder = JITBuilder::with_isa(isa, default_libcall_names());
        for f in Call1::ALL {
            let (name, address) = f.symbol();
            builder.symbol(name, address);
        }
        for f in Call2::ALL {
            let (name, address) = f.symbol();
            builder.symbol(name, address);
        }
        Ok(Self {
            module: JITModule::new(builder),
        })
    }

    /// Compiles `tape` as the function `name`.
    pub(crate) fn add(&mut self, name: &str, tape: &Tape) -> Result<FuncId, String> {
        let pointer = self.module.target_config().pointer_type();
        let mut signature = self.module.make_signature();
        signature.params.extend([
            AbiParam::new(pointer),
            AbiParam::new(pointer),
            AbiParam::new(pointer),
            AbiParam::new(types::F64),
        ]);
        signature.returns.push(AbiParam::new(types::I32));
        let id = self
            .module
            .declare_function(name, Linkage::Local, &signature)
            .map_err(|e| e.to_string())?;
        let mut context = self.module.make_context();
        context.func.signature = signature;
        let mut builder_context = FunctionBuilderContext::new();
        let mut builder = FunctionBuilder::new(&mut context.func, &mut builder_context);
        let mut writer = Writer::start(&mut builder, &mut self.module)?;
        writer.body(tape)?;
        builder.finalize(self.module.target_config());
        self.module
            .define_function(id, &mut context)
            .map_err(|e| format!("{e:?}"))?;
        Ok(id)
    }

    /// Finishes the function added: its address, and the code that owns it.
    pub(crate) fn finish(mut self, id: FuncId) -> Result<(KernelFn, Code), String> {
        self.module
            .finalize_definitions()
            .map_err(|e| e.to_string())?;
        let address = self.module.get_finalized_function(id);
        // SAFETY: `address` is the entry of a function compiled with exactly
        // the `KernelFn` signature (see `add`).
        let function = unsafe { std::mem::transmute::<*const u8, KernelFn>(address) };
        Ok((
            function,
            Code {
                module: Some(self.module),
            },
        ))
    }
}

/// Writes one function body.
struct Writer<'a, 'b> {
    builder: &'a mut FunctionBuilder<'b>,
    module: &'a mut JITModule,
    x: Value,
    dx: Value,
    inputs: Value,
    step: Value,
    bail: Block,
    calls1: Vec<(Call1, FuncRef)>,
    calls2: Vec<(Call2, FuncRef)>,
}

impl<'a, 'b> Writer<'a, 'b> {
    fn start(
        builder: &'a mut FunctionBuilder<'b>,
        module: &'a mut JITModule,
    ) -> Result<Self, String> {
        let entry = builder.create_block();
        builder.append_block_params_for_function_params(entry);
        builder.switch_to_block(entry);
        builder.seal_block(entry);
        let params = builder.block_params(entry).to_vec();
        let bail = builder.create_block();
        Ok(Self {
            builder,
            module,
            x: params[0],
            dx: params[1],
            inputs: params[2],
            step: params[3],
            bail,
            calls1: Vec::new(),
            calls2: Vec::new(),
        })
    }

    fn body(&mut self, tape: &Tape) -> Result<(), String> {
        let mut values: Vec<Option<Value>> = vec![None; tape.nodes.len()];
        for i in tape.schedule() {
            values[i] = Some(self.node(&tape.nodes[i], &values)?);
        }
        // Every value is computed (pure operations, whatever the branches);
        // the guards decide whether any is stored.
        for (_, guard) in &tape.guards {
            self.guard(guard, &values)?;
        }
        let memory = MemFlagsData::trusted();
        for &(output, node) in &tape.outputs {
            let value = value_of(&values, node)?;
            let (base, index) = match output {
                Output::Derivative(k) => (self.dx, k),
                Output::State(k) => (self.x, k),
            };
            self.builder
                .ins()
                .store(memory, value, base, offset(index)?);
        }
        let done = self.builder.ins().iconst(types::I32, 0);
        self.builder.ins().return_(&[done]);
        self.builder.switch_to_block(self.bail);
        self.builder.seal_block(self.bail);
        let gave_up = self.builder.ins().iconst(types::I32, 1);
        self.builder.ins().return_(&[gave_up]);
        Ok(())
    }

    fn node(&mut self, node: &Node, values: &[Option<Value>]) -> Result<Value, String> {
        let at = |id| value_of(values, id);
        let memory = MemFlagsData::trusted();
        Ok(match *node {
            Node::Const(c) => self.builder.ins().f64const(c),
            Node::Input(Slot::State(k)) => {
                self.builder
                    .ins()
                    .load(types::F64, memory, self.x, offset(k)?)
            }
            Node::Input(Slot::Input(k)) => {
                self.builder
                    .ins()
                    .load(types::F64, memory, self.inputs, offset(k)?)
            }
            Node::Input(Slot::Step) => self.step,
            Node::Neg(a) => self.builder.ins().fneg(at(a)?),
            Node::Abs(a) => self.builder.ins().fabs(at(a)?),
            Node::Sqrt(a) => self.builder.ins().sqrt(at(a)?),
            Node::Add(a, b) => self.builder.ins().fadd(at(a)?, at(b)?),
            Node::Sub(a, b) => self.builder.ins().fsub(at(a)?, at(b)?),
            Node::Mul(a, b) => self.builder.ins().fmul(at(a)?, at(b)?),
            Node::Div(a, b) => self.builder.ins().fdiv(at(a)?, at(b)?),
            Node::Call1(Call1::Powi(n), a) => {
                let f = self.function1(Call1::Powi(n))?;
                let exponent = self.builder.ins().f64const(n as f64);
                self.call(f, &[at(a)?, exponent])
            }
            Node::Call1(function, a) => {
                let f = self.function1(function)?;
                self.call(f, &[at(a)?])
            }
            Node::Call2(function, a, b) => {
                let f = self.function2(function)?;
                self.call(f, &[at(a)?, at(b)?])
            }
            Node::Sign(a) => {
                let a = at(a)?;
                let zero = self.builder.ins().f64const(0.0);
                let one = self.builder.ins().f64const(1.0);
                let signed = self.builder.ins().fcopysign(one, a);
                let at_zero = self.builder.ins().fcmp(FloatCC::Equal, a, zero);
                self.builder.ins().select(at_zero, zero, signed)
            }
        })
    }

    fn call(&mut self, f: FuncRef, arguments: &[Value]) -> Value {
        let call = self.builder.ins().call(f, arguments);
        self.builder.inst_results(call)[0]
    }

    /// A branch to the bail-out block unless the guard holds.
    fn guard(&mut self, guard: &Guard, values: &[Option<Value>]) -> Result<(), String> {
        let (a, b) = (value_of(values, guard.a)?, value_of(values, guard.b)?);
        let condition = match guard.holds {
            Holds::Equal => FloatCC::Equal,
            Holds::NotEqual => FloatCC::NotEqual,
            Holds::Less => FloatCC::LessThan,
            Holds::Greater => FloatCC::GreaterThan,
            Holds::Unordered => FloatCC::Unordered,
        };
        let holds = self.builder.ins().fcmp(condition, a, b);
        let next = self.builder.create_block();
        self.builder.ins().brif(holds, next, &[], self.bail, &[]);
        self.builder.switch_to_block(next);
        self.builder.seal_block(next);
        Ok(())
    }

    fn function1(&mut self, function: Call1) -> Result<FuncRef, String> {
        let key = match function {
            Call1::Powi(_) => Call1::Powi(0),
            other => other,
        };
        if let Some((_, f)) = self.calls1.iter().find(|(c, _)| *c == key) {
            return Ok(*f);
        }
        let arguments = if matches!(key, Call1::Powi(_)) { 2 } else { 1 };
        let f = self.import(key.symbol().0, arguments)?;
        self.calls1.push((key, f));
        Ok(f)
    }

    fn function2(&mut self, function: Call2) -> Result<FuncRef, String> {
        if let Some((_, f)) = self.calls2.iter().find(|(c, _)| *c == function) {
            return Ok(*f);
        }
        let f = self.import(function.symbol().0, 2)?;
        self.calls2.push((function, f));
        Ok(f)
    }

    fn import(&mut self, name: &str, arguments: usize) -> Result<FuncRef, String> {
        let mut signature: Signature = self.module.make_signature();
        signature
            .params
            .extend((0..arguments).map(|_| AbiParam::new(types::F64)));
        signature.returns.push(AbiParam::new(types::F64));
        let id = self
            .module
            .declare_function(name, Linkage::Import, &signature)
            .map_err(|e| e.to_string())?;
        Ok(self.module.declare_func_in_func(id, self.builder.func))
    }
}

fn value_of(values: &[Option<Value>], id: u32) -> Result<Value, String> {
    values
        .get(id as usize)
        .copied()
        .flatten()
        .ok_or_else(|| format!("node {id} used before it was computed"))
}

/// Byte offset of entry `index` of a `double` array.
fn offset(index: u32) -> Result<i32, String> {
    i32::try_from(index as u64 * 8).map_err(|_| format!("entry {index} is out of reach"))
}
