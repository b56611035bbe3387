//! CVODE from SUNDIALS as a peer of the bench: the same model, the same
//! excitation and tolerances, integrated by CVODE's BDF (Newton iteration with
//! a dense linear solver and the model's exact Jacobian) or its Adams method
//! (fixed-point iteration). SUNDIALS is opened at run time (Debian's
//! `libsundials-dev`, version 6): it is not a dependency of the program, and
//! without it the bench says so and goes on.
//!
//! The right-hand side CVODE calls is the model's own (`Model::rhs`, the
//! compiled one where the model compiles, as the native engines call it),
//! with no adaptor in between beyond reading the excitation, so the
//! comparison is between the integrators. CVODE restarts at every discontinuity of the
//! inputs (`CVodeReInit` at a stop time), as the native driver does, and its
//! samples come from its own interpolation (`CV_NORMAL`).

use std::ffi::{c_int, c_long, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

use fistage_model::{Inputs, Model, Workspace};
use fistage_sim::{Excitation, SimSettings, StepCounts, Trajectory, sample_times};
use libloading::{Library, Symbol};

/// Which CVODE method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CvodeMethod {
    /// Variable-order BDF (orders 1 to 5), Newton iteration, dense LU with the
    /// model's exact Jacobian (dual numbers).
    Bdf,
    /// Variable-order Adams-Moulton (orders 1 to 12), fixed-point iteration.
    Adams,
}

impl CvodeMethod {
    /// Label in the bench tables.
    pub fn label(self) -> &'static str {
        match self {
            Self::Bdf => "CVODE BDF, exact Jacobian",
            Self::Adams => "CVODE Adams, fixed point",
        }
    }
}

/// What a CVODE run gave.
pub struct CvodeRun {
    /// Samples on the scenario's grid.
    pub trajectory: Trajectory,
    /// Steps, error-test failures (as rejections) and right-hand sides.
    pub counts: StepCounts,
    /// Jacobian evaluations (BDF), each the cost of about n dual-number right-hand sides.
    pub jacobians: u64,
}

type RealType = f64;
type IndexType = i64;
type Opaque = *mut c_void;
type RhsFn = unsafe extern "C" fn(RealType, Opaque, Opaque, *mut c_void) -> c_int;
type JacFn = unsafe extern "C" fn(
    RealType,
    Opaque,
    Opaque,
    Opaque,
    *mut c_void,
    Opaque,
    Opaque,
    Opaque,
) -> c_int;

const CV_ADAMS: c_int = 1;
const CV_BDF: c_int = 2;
const CV_NORMAL: c_int = 1;

/// The SUNDIALS functions the harness calls, resolved once.
pub struct Cvode {
    _library: Library,
    context_create: unsafe extern "C" fn(*mut c_void, *mut Opaque) -> c_int,
    context_free: unsafe extern "C" fn(*mut Opaque) -> c_int,
    new_serial: unsafe extern "C" fn(IndexType, Opaque) -> Opaque,
    array_pointer: unsafe extern "C" fn(Opaque) -> *mut RealType,
    destroy_vector: unsafe extern "C" fn(Opaque),
    create: unsafe extern "C" fn(c_int, Opaque) -> Opaque,
    init: unsafe extern "C" fn(Opaque, RhsFn, RealType, Opaque) -> c_int,
    reinit: unsafe extern "C" fn(Opaque, RealType, Opaque) -> c_int,
    sv_tolerances: unsafe extern "C" fn(Opaque, RealType, Opaque) -> c_int,
    set_user_data: unsafe extern "C" fn(Opaque, *mut c_void) -> c_int,
    set_max_num_steps: unsafe extern "C" fn(Opaque, c_long) -> c_int,
    set_stop_time: unsafe extern "C" fn(Opaque, RealType) -> c_int,
    set_max_step: unsafe extern "C" fn(Opaque, RealType) -> c_int,
    dense_matrix: unsafe extern "C" fn(IndexType, IndexType, Opaque) -> Opaque,
    dense_column: unsafe extern "C" fn(Opaque, IndexType) -> *mut RealType,
    destroy_matrix: unsafe extern "C" fn(Opaque),
    dense_solver: unsafe extern "C" fn(Opaque, Opaque, Opaque) -> Opaque,
    free_linear_solver: unsafe extern "C" fn(Opaque) -> c_int,
    set_linear_solver: unsafe extern "C" fn(Opaque, Opaque, Opaque) -> c_int,
    set_jacobian: unsafe extern "C" fn(Opaque, JacFn) -> c_int,
    fixed_point: unsafe extern "C" fn(Opaque, c_int, Opaque) -> Opaque,
    free_nonlinear_solver: unsafe extern "C" fn(Opaque) -> c_int,
    set_nonlinear_solver: unsafe extern "C" fn(Opaque, Opaque) -> c_int,
    solve: unsafe extern "C" fn(Opaque, RealType, Opaque, *mut RealType, c_int) -> c_int,
    num_steps: unsafe extern "C" fn(Opaque, *mut c_long) -> c_int,
    num_rhs: unsafe extern "C" fn(Opaque, *mut c_long) -> c_int,
    num_error_fails: unsafe extern "C" fn(Opaque, *mut c_long) -> c_int,
    num_jacobians: unsafe extern "C" fn(Opaque, *mut c_long) -> c_int,
    free: unsafe extern "C" fn(*mut Opaque),
}

/// Where Debian puts CVODE (SUNDIALS 6), tried in turn.
const LIBRARY_NAMES: [&str; 2] = ["libsundials_cvode.so.6", "libsundials_cvode.so"];

impl Cvode {
    /// Opens SUNDIALS CVODE; the error says what was tried.
    pub fn open() -> Result<Self, String> {
        if let Some(why) = super::hidden() {
            return Err(format!("SUNDIALS CVODE {why}"));
        }
        let mut failures = Vec::new();
        for name in LIBRARY_NAMES {
            // SAFETY: loading a shared library runs its initialisers; SUNDIALS'
            // have no side effects beyond its own state.
            match unsafe { Library::new(name) } {
                Ok(library) => return Self::resolve(library).map_err(|e| format!("{name}: {e}")),
                Err(e) => failures.push(format!("{name}: {e}")),
            }
        }
        Err(format!(
            "SUNDIALS CVODE not found (install Debian's libsundials-dev): {}",
            failures.join("; ")
        ))
    }

    fn resolve(library: Library) -> Result<Self, libloading::Error> {
        // Each symbol is looked up by its C name and given the signature of
        // SUNDIALS 6.4's headers (realtype double, sunindextype int64).
        {
            fn get<T: Copy>(library: &Library, name: &[u8]) -> Result<T, libloading::Error> {
                // SAFETY: the caller names the signature of the symbol.
                let symbol: Symbol<T> = unsafe { library.get(name)? };
                Ok(*symbol)
            }
            Ok(Self {
                context_create: get(&library, b"SUNContext_Create\0")?,
                context_free: get(&library, b"SUNContext_Free\0")?,
                new_serial: get(&library, b"N_VNew_Serial\0")?,
                array_pointer: get(&library, b"N_VGetArrayPointer\0")?,
                destroy_vector: get(&library, b"N_VDestroy\0")?,
                create: get(&library, b"CVodeCreate\0")?,
                init: get(&library, b"CVodeInit\0")?,
                reinit: get(&library, b"CVodeReInit\0")?,
                sv_tolerances: get(&library, b"CVodeSVtolerances\0")?,
                set_user_data: get(&library, b"CVodeSetUserData\0")?,
                set_max_num_steps: get(&library, b"CVodeSetMaxNumSteps\0")?,
                set_stop_time: get(&library, b"CVodeSetStopTime\0")?,
                set_max_step: get(&library, b"CVodeSetMaxStep\0")?,
                dense_matrix: get(&library, b"SUNDenseMatrix\0")?,
                dense_column: get(&library, b"SUNDenseMatrix_Column\0")?,
                destroy_matrix: get(&library, b"SUNMatDestroy\0")?,
                dense_solver: get(&library, b"SUNLinSol_Dense\0")?,
                free_linear_solver: get(&library, b"SUNLinSolFree\0")?,
                set_linear_solver: get(&library, b"CVodeSetLinearSolver\0")?,
                set_jacobian: get(&library, b"CVodeSetJacFn\0")?,
                fixed_point: get(&library, b"SUNNonlinSol_FixedPoint\0")?,
                free_nonlinear_solver: get(&library, b"SUNNonlinSolFree\0")?,
                set_nonlinear_solver: get(&library, b"CVodeSetNonlinearSolver\0")?,
                solve: get(&library, b"CVode\0")?,
                num_steps: get(&library, b"CVodeGetNumSteps\0")?,
                num_rhs: get(&library, b"CVodeGetNumRhsEvals\0")?,
                num_error_fails: get(&library, b"CVodeGetNumErrTestFails\0")?,
                num_jacobians: get(&library, b"CVodeGetNumJacEvals\0")?,
                free: get(&library, b"CVodeFree\0")?,
                _library: library,
            })
        }
    }

    /// Integrates the model from `x0` over the settings' span with `method`.
    pub fn simulate(
        &self,
        method: CvodeMethod,
        model: &Model,
        x0: &[f64],
        excitation: &dyn Excitation,
        settings: &SimSettings,
    ) -> Result<CvodeRun, String> {
        let mut session = Session::new(self, method, model, x0, excitation, settings)?;
        let result = session.run();
        session.close();
        result
    }
}

/// What the callbacks read: the model and the excitation.
struct Plant<'a> {
    model: &'a Model,
    excitation: &'a dyn Excitation,
    workspace: Workspace,
    /// The inputs when they do not change with time.
    constant: Option<Inputs>,
    cvode: &'a Cvode,
}

impl Plant<'_> {
    fn inputs(&self, t: f64) -> Inputs {
        self.constant.unwrap_or_else(|| self.excitation.inputs(t))
    }
}

/// The right-hand side CVODE calls.
unsafe extern "C" fn rhs(t: RealType, y: Opaque, ydot: Opaque, data: *mut c_void) -> c_int {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: `data` is the Plant the session registered; the vectors are
        // serial vectors of the model's length.
        let plant = unsafe { &mut *(data as *mut Plant) };
        let n = plant.model.n_states();
        let (x, dx) = unsafe {
            (
                std::slice::from_raw_parts((plant.cvode.array_pointer)(y), n),
                std::slice::from_raw_parts_mut((plant.cvode.array_pointer)(ydot), n),
            )
        };
        plant
            .model
            .rhs(x, &plant.inputs(t), dx, &mut plant.workspace);
        if dx.iter().all(|v| v.is_finite()) {
            0
        } else {
            1
        }
    }));
    outcome.unwrap_or(-1)
}

/// The exact Jacobian (dual numbers through the same evaluation) CVODE's BDF asks for.
unsafe extern "C" fn jacobian(
    t: RealType,
    y: Opaque,
    _fy: Opaque,
    matrix: Opaque,
    data: *mut c_void,
    _tmp1: Opaque,
    _tmp2: Opaque,
    _tmp3: Opaque,
) -> c_int {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: as in `rhs`; the matrix is CVODE's n x n dense matrix.
        let plant = unsafe { &mut *(data as *mut Plant) };
        let n = plant.model.n_states();
        let x = unsafe { std::slice::from_raw_parts((plant.cvode.array_pointer)(y), n) };
        let jac = plant.model.jacobian(x, &plant.inputs(t));
        for col in 0..n {
            let column = unsafe {
                std::slice::from_raw_parts_mut((plant.cvode.dense_column)(matrix, col as i64), n)
            };
            for (row, entry) in column.iter_mut().enumerate() {
                *entry = jac[(row, col)];
            }
        }
        0
    }));
    outcome.unwrap_or(-1)
}

/// One CVODE integration and the SUNDIALS objects it owns.
struct Session<'a> {
    cvode: &'a Cvode,
    plant: Box<Plant<'a>>,
    context: Opaque,
    memory: Opaque,
    state: Opaque,
    tolerances: Opaque,
    matrix: Opaque,
    linear_solver: Opaque,
    nonlinear_solver: Opaque,
    settings: &'a SimSettings,
    n: usize,
}

impl<'a> Session<'a> {
    fn new(
        cvode: &'a Cvode,
        method: CvodeMethod,
        model: &'a Model,
        x0: &[f64],
        excitation: &'a dyn Excitation,
        settings: &'a SimSettings,
    ) -> Result<Self, String> {
        let n = model.n_states();
        // The machine code the native engines run (a model that does not
        // compile is evaluated generically by both).
        let _ = fistage_codegen::machine_code(model, fistage_codegen::Function::Rhs);
        let plant = Box::new(Plant {
            model,
            excitation,
            workspace: model.workspace(),
            constant: excitation.is_constant().then(|| excitation.inputs(0.0)),
            cvode,
        });
        let mut session = Session {
            cvode,
            plant,
            context: std::ptr::null_mut(),
            memory: std::ptr::null_mut(),
            state: std::ptr::null_mut(),
            tolerances: std::ptr::null_mut(),
            matrix: std::ptr::null_mut(),
            linear_solver: std::ptr::null_mut(),
            nonlinear_solver: std::ptr::null_mut(),
            settings,
            n,
        };
        // SAFETY: SUNDIALS objects are created in order and each checked;
        // `close` frees whatever was made, also after a failure here.
        unsafe {
            check(
                (cvode.context_create)(std::ptr::null_mut(), &mut session.context),
                "SUNContext_Create",
            )?;
            session.state = (cvode.new_serial)(n as i64, session.context);
            session.tolerances = (cvode.new_serial)(n as i64, session.context);
            if session.state.is_null() || session.tolerances.is_null() {
                return Err("N_VNew_Serial failed".into());
            }
            let y = std::slice::from_raw_parts_mut((cvode.array_pointer)(session.state), n);
            y.copy_from_slice(x0);
            let atol = std::slice::from_raw_parts_mut((cvode.array_pointer)(session.tolerances), n);
            for (a, nominal) in atol.iter_mut().zip(&model.layout().nominal) {
                *a = settings.rtol * settings.atol_scale * nominal;
            }
            let lmm = match method {
                CvodeMethod::Bdf => CV_BDF,
                CvodeMethod::Adams => CV_ADAMS,
            };
            session.memory = (cvode.create)(lmm, session.context);
            if session.memory.is_null() {
                return Err("CVodeCreate failed".into());
            }
            let memory = session.memory;
            check((cvode.init)(memory, rhs, 0.0, session.state), "CVodeInit")?;
            check(
                (cvode.sv_tolerances)(memory, settings.rtol, session.tolerances),
                "CVodeSVtolerances",
            )?;
            let data = &mut *session.plant as *mut Plant as *mut c_void;
            check((cvode.set_user_data)(memory, data), "CVodeSetUserData")?;
            let budget = c_long::try_from(settings.max_steps).unwrap_or(c_long::MAX);
            check(
                (cvode.set_max_num_steps)(memory, budget),
                "CVodeSetMaxNumSteps",
            )?;
            if let Some(h) = settings.max_step {
                check((cvode.set_max_step)(memory, h), "CVodeSetMaxStep")?;
            }
            match method {
                CvodeMethod::Bdf => {
                    session.matrix = (cvode.dense_matrix)(n as i64, n as i64, session.context);
                    session.linear_solver =
                        (cvode.dense_solver)(session.state, session.matrix, session.context);
                    if session.matrix.is_null() || session.linear_solver.is_null() {
                        return Err("dense matrix or solver failed".into());
                    }
                    check(
                        (cvode.set_linear_solver)(memory, session.linear_solver, session.matrix),
                        "CVodeSetLinearSolver",
                    )?;
                    check((cvode.set_jacobian)(memory, jacobian), "CVodeSetJacFn")?;
                }
                CvodeMethod::Adams => {
                    session.nonlinear_solver =
                        (cvode.fixed_point)(session.state, 0, session.context);
                    if session.nonlinear_solver.is_null() {
                        return Err("SUNNonlinSol_FixedPoint failed".into());
                    }
                    check(
                        (cvode.set_nonlinear_solver)(memory, session.nonlinear_solver),
                        "CVodeSetNonlinearSolver",
                    )?;
                }
            }
        }
        Ok(session)
    }

    /// Through the excitation's segments, sampling on the uniform grid.
    fn run(&mut self) -> Result<CvodeRun, String> {
        let settings = self.settings;
        let times = sample_times(settings.t_end, settings.sample_interval);
        let mut ends: Vec<f64> = self
            .plant
            .excitation
            .breakpoints()
            .into_iter()
            .filter(|&b| b > 0.0 && b < settings.t_end)
            .collect();
        ends.sort_by(f64::total_cmp);
        ends.dedup();
        ends.push(settings.t_end);
        let n = self.n;
        let mut trajectory = Trajectory::with_capacity(n, times.len());
        let cvode = self.cvode;
        // SAFETY: the session's objects are live; the state vector has n entries.
        unsafe {
            let y = (cvode.array_pointer)(self.state);
            trajectory.push(0.0, std::slice::from_raw_parts(y, n));
            let mut next = 1;
            let mut t = 0.0;
            for (segment, &stop) in ends.iter().enumerate() {
                if segment > 0 {
                    check((cvode.reinit)(self.memory, t, self.state), "CVodeReInit")?;
                }
                check((cvode.set_stop_time)(self.memory, stop), "CVodeSetStopTime")?;
                while next < times.len() && times[next] <= stop * (1.0 + 1e-14) {
                    let status =
                        (cvode.solve)(self.memory, times[next], self.state, &mut t, CV_NORMAL);
                    if status < 0 {
                        return Err(format!("CVode failed with flag {status} at t = {t:.6} s"));
                    }
                    trajectory.push(times[next], std::slice::from_raw_parts(y, n));
                    next += 1;
                }
                if t < stop {
                    let status = (cvode.solve)(self.memory, stop, self.state, &mut t, CV_NORMAL);
                    if status < 0 {
                        return Err(format!("CVode failed with flag {status} at t = {t:.6} s"));
                    }
                }
            }
            let read = |f: unsafe extern "C" fn(Opaque, *mut c_long) -> c_int| {
                let mut value: c_long = 0;
                f(self.memory, &mut value);
                value.max(0) as u64
            };
            let counts = StepCounts {
                steps: read(cvode.num_steps),
                rejected: read(cvode.num_error_fails),
                rhs_evaluations: read(cvode.num_rhs),
            };
            let jacobians = if self.linear_solver.is_null() {
                0
            } else {
                read(cvode.num_jacobians)
            };
            Ok(CvodeRun {
                trajectory,
                counts,
                jacobians,
            })
        }
    }

    /// Frees every SUNDIALS object the session made.
    fn close(&mut self) {
        let cvode = self.cvode;
        // SAFETY: each pointer is freed once, by its own destructor, and nulled.
        unsafe {
            if !self.memory.is_null() {
                (cvode.free)(&mut self.memory);
            }
            if !self.linear_solver.is_null() {
                (cvode.free_linear_solver)(self.linear_solver);
            }
            if !self.nonlinear_solver.is_null() {
                (cvode.free_nonlinear_solver)(self.nonlinear_solver);
            }
            if !self.matrix.is_null() {
                (cvode.destroy_matrix)(self.matrix);
            }
            for vector in [self.state, self.tolerances] {
                if !vector.is_null() {
                    (cvode.destroy_vector)(vector);
                }
            }
            if !self.context.is_null() {
                (cvode.context_free)(&mut self.context);
            }
        }
        self.linear_solver = std::ptr::null_mut();
        self.nonlinear_solver = std::ptr::null_mut();
        self.matrix = std::ptr::null_mut();
        self.state = std::ptr::null_mut();
        self.tolerances = std::ptr::null_mut();
    }
}

fn check(status: c_int, call: &str) -> Result<(), String> {
    if status < 0 {
        Err(format!("{call} returned {status}"))
    } else {
        Ok(())
    }
}
