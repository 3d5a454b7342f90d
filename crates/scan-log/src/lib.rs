//! Recorded laser data: CARMEN, BreezySLAM and MCAP logs read as a `LaserSource`,
//! and MCAP recording with the Foxglove `LaserScan` schema.
//!
//! Status: under construction; see the issue tracker. Nothing here is finished yet.
