//! End-to-end tests of FIRES live in `tests/`: each runs the simulator and then the stages after it (tracking
//! today; curve network and surface as they land) and checks the result against the simulator's ground truth.
//! This library is empty; see `tests/*.rs`.
