//! Fig. 3 at the default scale (40 realisations, N = 10 000), as JSON on stdout.
use pf_homotopy::experiments::{RmseConfig, Scale, rmse};

fn main() -> Result<(), pf_homotopy::HomotopyError> {
    let res = rmse(&RmseConfig::at_scale(Scale::Default))?;
    println!("{}", serde_json::to_string(&res).unwrap_or_default());
    Ok(())
}
