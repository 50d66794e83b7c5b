//! [`OnnxSegmenter`]: SCHP-compatible models on ONNX Runtime (loaded at run time).

use crate::ParsingError;
use crate::segmenter::{ParsedView, Segmenter, ViewInput};
use crate::spec::ModelSpec;
use crate::transform::{
    InputTransform, normalize_to_chw, upsample_logits, warp_back_and_classify, warp_to_input,
};
use bodyseg_core::{Label, LabelImage, NUM_CLASSES};
use ort::environment::Environment;
use ort::session::Session;
use ort::session::SessionOutputs;
use ort::session::builder::GraphOptimizationLevel;
use ort::value::{PrimitiveTensorElementType, Shape, Tensor, TensorRef, ValueType};
use std::fmt::Debug;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

mod prune;
pub(crate) use prune::without_outputs;

/// How an [`OnnxSegmenter`] runs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OnnxOptions {
    /// ONNX Runtime intra-op threads; 0 lets ONNX Runtime choose (one per core).
    pub threads: usize,
    /// Also return all 7 class probabilities per pixel ([`ParsedView::class_probs`]).
    pub keep_class_probs: bool,
}

impl Default for OnnxOptions {
    fn default() -> Self {
        OnnxOptions {
            threads: 2,
            keep_class_probs: false,
        }
    }
}

/// The process's ONNX Runtime environment and the library it came from. ONNX Runtime
/// allows one environment per process; it is created by the first [`load_runtime`].
static RUNTIME: Mutex<Option<(Environment, PathBuf)>> = Mutex::new(None);

/// [`ParsingError::Inference`] for `cause`, naming the model file `path`.
pub(crate) fn inference_error(path: &Path, cause: String) -> ParsingError {
    ParsingError::Inference {
        cause,
        path: path.to_path_buf(),
    }
}

/// One run of `session` on the tensor `data` of `shape`, fed to the input `input_name`
/// (BlazePose's and BodyPix's crops: one NHWC image each); errors name `path`.
pub(crate) fn run_one_input<'s, T: PrimitiveTensorElementType + Debug + Clone + 'static>(
    session: &'s mut Session,
    input_name: &'static str,
    shape: [usize; 4],
    data: &[T],
    path: &Path,
) -> Result<SessionOutputs<'s>, ParsingError> {
    let tensor = TensorRef::from_array_view((shape, data))
        .map_err(|e| inference_error(path, e.to_string()))?;
    session
        .run(ort::inputs![input_name => tensor])
        .map_err(|e| inference_error(path, e.to_string()))
}

/// The output `name` of `outputs` as its shape and values of type `T`; errors (no such
/// output, another element type) name `path`.
pub(crate) fn named_output<'o, T: PrimitiveTensorElementType>(
    outputs: &'o SessionOutputs<'_>,
    name: &str,
    path: &Path,
) -> Result<(&'o Shape, &'o [T]), ParsingError> {
    let value = outputs
        .get(name)
        .ok_or_else(|| inference_error(path, format!("no output {name}")))?;
    value
        .try_extract_tensor::<T>()
        .map_err(|e| inference_error(path, format!("{name}: {e}")))
}

/// A session of `model_bytes` (`model_path` names it in errors) in the ONNX Runtime of
/// `runtime_library`: full graph optimisation, `threads` intra-op threads (0 lets ONNX
/// Runtime choose), one inter-op thread, the intra-op pool spinning or not (`spin`).
///
/// # Errors
/// [`ParsingError::RuntimeLibrary`], [`ParsingError::ModelLoad`].
pub(crate) fn load_session(
    runtime_library: &Path,
    model_bytes: &[u8],
    model_path: &Path,
    threads: usize,
    spin: bool,
) -> Result<Session, ParsingError> {
    let env = load_runtime(runtime_library)?;
    let load_err = |cause: String| ParsingError::ModelLoad {
        cause,
        path: model_path.to_path_buf(),
    };
    Session::builder(&env)
        .map_err(|e| load_err(e.to_string()))?
        .with_optimization_level(GraphOptimizationLevel::Level3)
        .map_err(|e| load_err(e.to_string()))?
        .with_intra_threads(threads)
        .map_err(|e| load_err(e.to_string()))?
        .with_inter_threads(1)
        .map_err(|e| load_err(e.to_string()))?
        .with_intra_op_spinning(spin)
        .map_err(|e| load_err(e.to_string()))?
        .commit_from_memory(model_bytes)
        .map_err(|e| load_err(e.to_string()))
}

/// Loads the ONNX Runtime shared library `library` (once per process) and returns the
/// environment sessions are created in. Later calls return the first environment, even
/// with another path (ONNX Runtime cannot be unloaded); that is logged at debug level.
///
/// # Errors
/// [`ParsingError::RuntimeLibrary`] naming `library` when it is missing, not a shared
/// library, or older than the API version ort needs (ONNX Runtime 1.17).
pub fn load_runtime(library: &Path) -> Result<Environment, ParsingError> {
    let mut runtime = RUNTIME
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    if let Some((env, loaded)) = runtime.as_ref() {
        if loaded != library {
            tracing::debug!(
                loaded = %loaded.display(),
                asked = %library.display(),
                "ONNX Runtime already loaded; keeping it"
            );
        }
        return Ok(env.clone());
    }
    let err = |cause: String| ParsingError::RuntimeLibrary {
        cause,
        path: library.to_path_buf(),
    };
    let env = ort::init_from(library)
        .map_err(|e| err(e.to_string()))?
        .with_name("bodyseg")
        .build()
        .map_err(|e| err(e.to_string()))?;
    tracing::debug!(library = %library.display(), "loaded ONNX Runtime");
    *runtime = Some((env.clone(), library.to_path_buf()));
    Ok(env)
}

/// A parsing network in ONNX following the contract of ALGORITHM.md §2, with SCHP's pre-
/// and post-processing ([`crate::transform`]). All views of a frame go through the network
/// in one batch (or in batches of the model's fixed batch size).
pub struct OnnxSegmenter {
    session: Session,
    spec: ModelSpec,
    model_path: PathBuf,
    options: OnnxOptions,
    /// The model's fixed batch size, `None` when the batch dimension is dynamic.
    fixed_batch: Option<usize>,
}

impl std::fmt::Debug for OnnxSegmenter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OnnxSegmenter")
            .field("model_path", &self.model_path)
            .field("spec", &self.spec)
            .field("options", &self.options)
            .field("fixed_batch", &self.fixed_batch)
            .finish_non_exhaustive()
    }
}

/// The dims of a float32 tensor outlet, `-1` for dynamic ones; `None` for another type.
pub(crate) fn float_dims(dtype: &ValueType) -> Option<Vec<i64>> {
    match dtype {
        ValueType::Tensor { ty, shape, .. } if *ty == ort::value::TensorElementType::Float32 => {
            Some(shape.to_vec())
        }
        _ => None,
    }
}

impl OnnxSegmenter {
    /// Loads a model from its bytes (read by the caller; `model_path` names it in errors)
    /// and its sidecar `spec`, in the ONNX Runtime of `runtime_library`
    /// ([`load_runtime`]), and checks it against the contract: one float32 input
    /// `[N,3,S,S]` with S the sidecar's input size, a float32 output `[N,7,h,w]` whose size
    /// fits the sidecar's `output_stride` (dims the model leaves dynamic are checked at
    /// the first run).
    ///
    /// # Errors
    /// [`ParsingError::RuntimeLibrary`], [`ParsingError::ModelLoad`],
    /// [`ParsingError::ModelContract`], [`ParsingError::OutputChannels`],
    /// [`ParsingError::Sidecar`] (the model's input or output size disagrees with it).
    pub fn new(
        runtime_library: &Path,
        model_bytes: &[u8],
        model_path: &Path,
        spec: ModelSpec,
        options: &OnnxOptions,
    ) -> Result<OnnxSegmenter, ParsingError> {
        let session = load_session(
            runtime_library,
            model_bytes,
            model_path,
            options.threads,
            true,
        )?;
        let contract = |reason: String| ParsingError::ModelContract {
            reason,
            path: model_path.to_path_buf(),
        };
        let sidecar = |field: &'static str, reason: String| ParsingError::Sidecar {
            field,
            reason,
            path: crate::spec::sidecar_path(model_path),
        };
        // The dims of a float32 tensor of rank 4, or an error naming the input or output.
        let four_dims = |what: &str, name: &str, dtype: &ValueType, expected: &str| {
            float_dims(dtype)
                .filter(|d| d.len() == 4)
                .ok_or_else(|| contract(format!("{what} {name} is {dtype:?}, expected {expected}")))
        };
        if session.inputs().len() != 1 {
            return Err(contract(format!(
                "it has {} inputs, expected 1 ([N,3,H,W] float32)",
                session.inputs().len()
            )));
        }
        let input = &session.inputs()[0];
        let dims = four_dims(
            "input",
            input.name(),
            input.dtype(),
            "a float32 tensor [N,3,H,W]",
        )?;
        if dims[1] != 3 && dims[1] != -1 {
            return Err(contract(format!(
                "input {} has {} channels, expected 3",
                input.name(),
                dims[1]
            )));
        }
        let s = i64::from(spec.input_side());
        if dims[2..].iter().any(|&d| d != -1 && d != s) {
            return Err(sidecar(
                "input_size",
                format!(
                    "is [{s}, {s}] but the model's input is {}x{}",
                    dims[2], dims[3]
                ),
            ));
        }
        let fixed_batch = (dims[0] > 0).then_some(dims[0] as usize);
        let Some(output) = session.outputs().first() else {
            return Err(contract("it has no output".into()));
        };
        let out = four_dims(
            "output",
            output.name(),
            output.dtype(),
            "float32 logits [N,7,h,w]",
        )?;
        if out[1] != -1 && out[1] != NUM_CLASSES as i64 {
            return Err(ParsingError::OutputChannels {
                got: out[1],
                path: model_path.to_path_buf(),
            });
        }
        if out[2] > 0 && out[3] > 0 && !spec.output_size_fits(out[2] as u32, out[3] as u32) {
            return Err(sidecar(
                "output_stride",
                format!(
                    "is {} but the model's {s}x{s} input gives {}x{} logits",
                    spec.output_stride, out[2], out[3]
                ),
            ));
        }
        tracing::debug!(model = %model_path.display(), ?dims, ?out, "loaded parsing model");
        Ok(OnnxSegmenter {
            session,
            spec,
            model_path: model_path.to_path_buf(),
            options: options.clone(),
            fixed_batch,
        })
    }

    /// The model's sidecar.
    pub fn spec(&self) -> &ModelSpec {
        &self.spec
    }

    /// Runs the network on a batch of normalised inputs (`n` views, CHW each) and returns
    /// the logits `[n,7,h,w]` with `(h, w)`.
    ///
    /// # Errors
    /// [`ParsingError::Inference`], [`ParsingError::OutputChannels`],
    /// [`ParsingError::ModelContract`] for an output of unexpected shape.
    pub fn run_batch(
        &mut self,
        input: Vec<f32>,
        n: usize,
    ) -> Result<(Vec<f32>, usize, usize), ParsingError> {
        let s = self.spec.input_side() as usize;
        let path = self.model_path.clone();
        let infer = |cause: String| ParsingError::Inference {
            cause,
            path: path.clone(),
        };
        let tensor = Tensor::from_array(([n, 3, s, s], input)).map_err(|e| infer(e.to_string()))?;
        let outputs = self
            .session
            .run(ort::inputs![tensor])
            .map_err(|e| infer(e.to_string()))?;
        let (shape, data) = outputs[0]
            .try_extract_tensor::<f32>()
            .map_err(|e| infer(e.to_string()))?;
        let dims: &[i64] = shape;
        if dims.len() != 4 || dims[0] != n as i64 {
            return Err(ParsingError::ModelContract {
                reason: format!("output shape {dims:?} for a batch of {n}, expected [{n},7,h,w]"),
                path,
            });
        }
        if dims[1] != NUM_CLASSES as i64 {
            return Err(ParsingError::OutputChannels { got: dims[1], path });
        }
        let (h, w) = (dims[2] as usize, dims[3] as usize);
        if h == 0 || w == 0 || !self.spec.output_size_fits(h as u32, w as u32) {
            return Err(ParsingError::Sidecar {
                field: "output_stride",
                reason: format!(
                    "is {} but the model's {s}x{s} input gives {h}x{w} logits",
                    self.spec.output_stride
                ),
                path: crate::spec::sidecar_path(&path),
            });
        }
        Ok((data.to_vec(), h, w))
    }
}

impl Segmenter for OnnxSegmenter {
    fn segment(&mut self, views: &[ViewInput<'_>]) -> Result<Vec<ParsedView>, ParsingError> {
        let s = self.spec.input_side();
        let mut transforms = Vec::with_capacity(views.len());
        for (view, input) in views.iter().enumerate() {
            let image = input.checked_image(view)?;
            transforms.push((image, InputTransform::new(image.width, image.height, s)));
        }
        let batch = self.fixed_batch.unwrap_or(views.len().max(1));
        let plane = 3 * s as usize * s as usize;
        let mut parsed = Vec::with_capacity(views.len());
        for chunk in transforms.chunks(batch) {
            let mut input = Vec::with_capacity(batch * plane);
            for (image, t) in chunk {
                normalize_to_chw(&warp_to_input(image, t), &self.spec, &mut input);
            }
            // A fixed-batch model gets a full batch: pad with zeros (results dropped).
            let n = if self.fixed_batch.is_some() {
                batch
            } else {
                chunk.len()
            };
            input.resize(n * plane, 0.0);
            let (logits, h, w) = self.run_batch(input, n)?;
            for (i, (_, t)) in chunk.iter().enumerate() {
                let one = &logits[i * NUM_CLASSES * h * w..(i + 1) * NUM_CLASSES * h * w];
                let up = upsample_logits(one, h, w, s as usize, self.spec.align_corners);
                let px = warp_back_and_classify(&up, t, self.options.keep_class_probs);
                let labels = px
                    .class_ids
                    .iter()
                    .map(|&id| Label::from_id(id).unwrap_or(Label::BACKGROUND))
                    .collect();
                let labels = LabelImage {
                    width: t.width,
                    height: t.height,
                    labels,
                    probs: Some(px.probs),
                };
                parsed.push(ParsedView {
                    labels,
                    class_probs: px.class_probs,
                });
            }
        }
        Ok(parsed)
    }
}
