//! The λ-step and polar-grid ablation at the quick scale, as JSON.
use pf_homotopy::experiments::{AblationConfig, Scale, ablation};

fn main() -> Result<(), pf_homotopy::HomotopyError> {
    let res = ablation(&AblationConfig::at_scale(Scale::Quick))?;
    println!("{res:?}");
    Ok(())
}
