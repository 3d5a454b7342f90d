//! Path choice: which ray to follow toward the target (the paper's greedy rule, or path
//! length over the map built so far), the rotation alpha and the safe travel distance.
//!
//! Status: under construction; see the issue tracker. Nothing here is finished yet.
