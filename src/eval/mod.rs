//! The paper's evaluation: PSNR of sampling strategies and reconstructions.
