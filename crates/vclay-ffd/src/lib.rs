//! vclay-ffd (in progress)
