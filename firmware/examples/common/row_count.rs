//! Instructions of a frame, summed row by row: a whole frame can pass the Arm SysTick
//! counter's 671 M-instruction wrap (`arch`), a row cannot. The sink's own work is not counted.

use crate::arch;
use scanline3d::sink::{Row, RowSink};

/// Wraps a sink and adds up the instructions spent between the rows it receives.
pub struct RowCounted<K> {
    /// The wrapped sink.
    pub sink: K,
    mark: arch::Mark,
    /// Instructions since [`RowCounted::new`], up to the last row.
    pub instructions: u64,
}

impl<K> RowCounted<K> {
    /// Starts counting now.
    pub fn new(sink: K) -> Self {
        RowCounted {
            sink,
            mark: arch::start(),
            instructions: 0,
        }
    }
}

impl<P, K: RowSink<P>> RowSink<P> for RowCounted<K> {
    type Error = K::Error;
    fn write_row(&mut self, row: Row<'_, P>) -> Result<(), Self::Error> {
        self.instructions += arch::instructions(&self.mark);
        let result = self.sink.write_row(row);
        self.mark = arch::start();
        result
    }
}
