//! vclay-lattice (in progress)
