//! Who is on the road and who waits to enter: the vehicle records of a run, the queues of vehicles waiting at
//! their entry, and the initial vehicles' places. Data only; the simulator's insertion (`sim/entry/`) uses them.

pub mod placement;
pub mod vehicle_table;
pub mod waiting;
