//! Landmarks in raw scans: the paper's max-range jumps, occlusion edges and corners;
//! stability rules, selection (eq. 6) and tracking while the robot drives.
//!
//! Status: under construction; see the issue tracker. Nothing here is finished yet.
