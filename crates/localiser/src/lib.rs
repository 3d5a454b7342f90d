//! Localisation without odometry: the triangles OBC and OAB give point B, the scan measures
//! the rotation, and localised scans build a point map and an occupancy grid.
//!
//! Status: under construction; see the issue tracker. Nothing here is finished yet.
