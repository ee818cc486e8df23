//! How often a tracked state that contradicts the images is replaced by a
//! rope found again: recoveries in a row back off.

/// Longest wait, in frames, between recoveries from steps that contradict
/// the images (`2^k - 1` frames after the `k`-th recovery in a row): a
/// recovery costs a whole initialisation (10-50 ms at 1280x720, against
/// half a millisecond for a step), so a state that keeps contradicting
/// the images costs at most about one initialisation in this many frames,
/// yet is still retried. 63 frames: two seconds at 30 frames/s.
pub const MAX_RECOVERY_WAIT: u32 = 63;

/// How often a state that contradicts the images is re-initialised: after
/// the `k`-th recovery in a row, the next waits `2^k - 1` frames (at most
/// [`MAX_RECOVERY_WAIT`]); a step that agrees with the images ends the row.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RecoveryBackoff {
    /// Recoveries since the last step that agreed with the images.
    in_a_row: u32,
    /// Frames still to wait before the next recovery.
    wait: u32,
}

impl RecoveryBackoff {
    /// `true` when a recovery may run on this frame; else one frame of the
    /// wait passes.
    pub(super) fn may_recover(&mut self) -> bool {
        if self.wait == 0 {
            return true;
        }
        self.wait -= 1;
        false
    }

    /// A recovery ran (taken or not): the next one waits longer.
    pub(super) fn recovered(&mut self) {
        self.in_a_row = self.in_a_row.saturating_add(1);
        self.wait = 1u32
            .checked_shl(self.in_a_row)
            .map_or(MAX_RECOVERY_WAIT, |w| (w - 1).min(MAX_RECOVERY_WAIT));
    }

    /// A step agreed with the images: recoveries run at once again.
    pub(super) fn agreed(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;

    #[test]
    fn recoveries_in_a_row_back_off_exponentially_up_to_the_cap() {
        let mut b = RecoveryBackoff::default();
        let mut ran = Vec::new();
        for frame in 0..200 {
            if b.may_recover() {
                ran.push(frame);
                b.recovered();
            }
        }
        assert_eq!(ran[..7], [0, 2, 6, 14, 30, 62, 126]);
        let gaps: Vec<u32> = ran.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps.iter().all(|&g| g <= MAX_RECOVERY_WAIT + 1), "{gaps:?}");
        assert_eq!(gaps.last(), Some(&(MAX_RECOVERY_WAIT + 1)));
        b.agreed();
        assert!(b.may_recover());
        for _ in 0..100 {
            b.recovered();
        }
        assert_eq!(b.wait, MAX_RECOVERY_WAIT);
    }
}
