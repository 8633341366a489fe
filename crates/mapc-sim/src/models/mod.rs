//! The drivers' models, after SUMO's `src/microsim/cfmodels/` and `models/lc/`: how a driver follows (car
//! following, [`cf`]) and when it changes lanes (lane changing, [`lc`]), one model per file behind a small
//! interface. The step asks the models; the models know nothing of the step.

pub mod cf;
pub mod lc;
