//! fistage-ident: LuGre identification from f_ss(v) curves and FRFs (in progress).
