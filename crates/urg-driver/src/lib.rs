//! Hokuyo SCIP 2.0 driver: a pure codec, a driver generic over its transport that
//! implements `LaserSource`, and an emulator of the sensor side for tests and `robot-app emulate`.
//!
//! Status: under construction; see the issue tracker. Nothing here is finished yet.
