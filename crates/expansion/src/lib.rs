//! The obstacle-expansion kernel of the paper (section 3, eqs. 1-5): every hit point grows
//! into a disc of the robot radius, and each ray gets its clearance to the first disc it enters.
//!
//! Status: under construction; see the issue tracker. Nothing here is finished yet.
