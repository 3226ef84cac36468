//! `sinscal import FORMAT ...`: a measured data set (PSINS .imu, imucal Ferraris session, imu_tk counts)
//! converted into a recording.

pub use crate::io::import::ImportArgs as Args;

/// Runs `sinscal import`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Err(usage) = args.validate() {
        usage.exit();
    }
    super::out(&crate::io::import::run(&args)?)?;
    Ok(())
}
